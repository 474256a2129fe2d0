#pragma once
// What the ARKODE integrators share (src/time/arkode.cpp: ERKStep; src/time/arkode_imex.cpp:
// ARKStep): the N_Vector over the system's state buffer, the scene's error-control tolerances
// and their per-field vector.
#include <sundials/sundials_context.h>
#include <sundials/sundials_nvector.h>

#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

// N_Vector over the state buffer y of n values (no copy): the OpenMP vector with fused
// operations for large states when threads are available, else the serial one.
N_Vector wrapState(double* y, std::size_t n, SUNContext context);

// The relative tolerance and the absolute tolerance of each field of the state (position,
// density, velocity, evolving fields), from [integrator] rtol, atol_* and reference_velocity.
struct ErrorTolerances {
  double rtol = 0;
  std::vector<double> atol_by_segment;  // position, density, velocity, evolving fields (stress)
};
ErrorTolerances readTolerances(ConfigTable& cfg, const ReferenceScales& scales);

// The absolute tolerance of every state value, by the segment it lies in.
void fillTolerances(double* atol, std::size_t n, const StateSegments& segments, const std::vector<double>& by_segment);

}  // namespace vesph
