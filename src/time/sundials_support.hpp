#pragma once
// What the ARKODE integrators share (src/time/arkode.cpp: ERKStep; src/time/arkode_imex.cpp:
// ARKStep): the N_Vector over the system's state buffer, the scene's error-control tolerances
// and their per-field vector.
#include <sundials/sundials_context.h>
#include <sundials/sundials_nvector.h>

#include <cmath>
#include <exception>
#include <string>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

// N_Vector over the state buffer y of n values (no copy): the OpenMP vector with fused
// operations for large states when threads are available, else the serial one.
// In a run across processes (communicator: OdeSystem::stateCommunicator) it is the local part
// of an MPIPlusX vector, whose norms span every process. Destroy it with destroyState.
N_Vector wrapState(double* y, std::size_t n, SUNContext context, const void* communicator = nullptr);
void destroyState(N_Vector v);

// The relative tolerance and the absolute tolerance of each field of the state (position,
// density, velocity, evolving fields), from [integrator] rtol, atol_* and reference_velocity.
struct ErrorTolerances {
  double rtol = 0;
  std::vector<double> atol_by_segment;  // position, density, velocity, evolving fields (stress)
};
ErrorTolerances readTolerances(ConfigTable& cfg, const ReferenceScales& scales);

// The absolute tolerance of every state value, by the segment it lies in.
void fillTolerances(double* atol, std::size_t n, const StateSegments& segments, const std::vector<double>& by_segment);

// ARKODE's name of a return flag (ERKStep and ARKStep share the flags), and an error for a
// set-up call that did not succeed.
std::string arkodeFlagName(int flag);
void checkArkode(int flag, const char* what);

// ARKODE multiplies the stability function's step by the CFL fraction, which must be below 1;
// vesph's limits carry their coefficients already, so the function returns the limit divided
// by this fraction (a non-positive value means "no limit").
inline constexpr double kArkodeCflFraction = 0.5;
inline double arkodeStabilityStep(double limit) { return std::isfinite(limit) ? limit / kArkodeCflFraction : -1.0; }

// What the integrators keep across ARKODE's C callbacks, which must not throw: a failure is kept
// and reported after *StepEvolve returns; the post-process function runs the system's
// afterStep with the step just taken.
struct ArkodeCallbackState {
  OdeSystem* sys = nullptr;
  double t_last_accepted = 0;
  bool stop_requested = false;
  std::string pending_error{};

  // fn() guarded: 0, or -1 with the exception's message kept.
  template <class F>
  int guarded(F&& fn) {
    try {
      fn();
      return 0;
    } catch (const std::exception& e) {
      pending_error = e.what();
      return -1;
    }
  }
  // The post-process function's body: afterStep with the step taken since the last accepted
  // one (inside it ARKODE's GetLastStep still reports the step before); -1 stops the run.
  int afterStep(double t, double* y) {
    const double h = t - t_last_accepted;
    t_last_accepted = t;
    bool go_on = true;
    if (guarded([&] { go_on = sys->afterStep(t, h, y); })) return -1;
    if (!go_on) stop_requested = true;
    return go_on ? 0 : -1;
  }
};

}  // namespace vesph
