#pragma once
// The integrator interface (docs/architecture.md "Integrators"); building one from the scene
// is vesph/time/integrator_factory.hpp. An integrator advances the ODE state
// y' = f(t, y) of an OdeSystem; it owns time, the system owns physics. All integrators
// respect the same explicit stability limits (stepLimits; the implicit-explicit ones those of
// the explicit part, OdeSystem::explicitStability) and call the system's afterStep after every
// accepted step (post-step hooks, diagnostics, failure checks).
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "vesph/core/types.hpp"

namespace vesph {

// Where the fields sit in the state vector: positions | densities | velocities | evolving
// fields (elastic stresses), the last from velocity_end to the end of the state. The leapfrog
// treats the groups differently; ARKODE gives each group its own absolute tolerance.
struct StateSegments {
  std::size_t position_begin = 0, position_end = 0;
  std::size_t velocity_begin = 0, velocity_end = 0;
};

// The quantities the explicit stability limits are made of, at the last rhs evaluation.
struct StabilitySnapshot {
  double h = 0;                    // smoothing length, m
  double sound_speed = 0;          // m/s (0 for schemes without one)
  double max_speed = 0;            // max |v| over moving particles, m/s
  double kinematic_viscosity = 0;  // m^2/s
  double max_acceleration = 0;     // max |dv/dt| over moving particles, m/s^2
  double elastic_wave_speed = 0;   // sqrt(G/rho) of elastic models, m/s
  double relaxation_time = 0;      // shortest relaxation time of elastic models, s (0: none)
};

// Coefficients of the limits, scene keys of [integrator]:
//   acoustic (CFL):  dt <= cfl * h / (c + c_e + v_max)        thesis 3.5, Fang eq. (51);
//                    c_e = sqrt(G/rho) the elastic shear-wave speed of viscoelastic models
//   viscous:         dt <= viscous_coefficient * h^2 / nu       Fang eq. (53)
//   force:           dt <= force_coefficient * sqrt(h / a_max)  Fang eq. (52)
//   relaxation:      dt <= relaxation_coefficient * lambda      explicit stability of the
//                    stress relaxation -S/lambda (stable up to dt = 2 lambda for 2nd-order schemes)
// fixed_step (integrator.step), when set, makes the fixed-step integrators take exactly that
// step (shortened only to land on output times) instead of the stability limit: for temporal
// convergence studies; the limits are not applied then.
// The default CFL coefficient of each pressure scheme (thesis §3.5): WCSPH's is StepControl's
// cfl; the incompressible scheme's projection allows a larger step.
inline constexpr double kWcsphDefaultCfl = 0.125;
inline constexpr double kIsphDefaultCfl = 0.175;
// The one-evaluation symplectic scheme's own WCSPH default (src/time/symplectic.cpp): stable up
// to 0.35 and unstable at 0.5 on a dam break and on the drop, so 0.175 keeps a factor 2
// (docs/performance.md "One evaluation per step").
inline constexpr double kSymplecticWcsphDefaultCfl = 0.175;

struct StepControl {
  double cfl = kWcsphDefaultCfl;
  double viscous_coefficient = 0.125;
  double force_coefficient = 0.25;
  double relaxation_coefficient = 0.5;
  double max_step = std::numeric_limits<double>::infinity();
  double fixed_step = 0.0;
};

// Scales of the problem, for default absolute tolerances of error-controlled integrators.
struct ReferenceScales {
  double spacing = 1;            // dx, m
  double density = 1;            // rho0, kg/m^3
  double density_variation = 0.01;  // delta (relative)
  double velocity = 0;           // expected speed, m/s (0: unknown)
  double stress = 0;             // expected elastic stress, Pa (0: none evolves)
};

struct StepLimits {
  double acoustic = std::numeric_limits<double>::infinity();
  double viscous = std::numeric_limits<double>::infinity();
  double force = std::numeric_limits<double>::infinity();
  double relaxation = std::numeric_limits<double>::infinity();
  double smallest() const;
};
StepLimits stepLimits(const StabilitySnapshot& s, const StepControl& c);

// A square sparse matrix in compressed rows (the diagonal first in each row).
struct CsrMatrix {
  std::vector<int> row_start{0};  // rows() + 1 entries
  std::vector<int> column;
  std::vector<double> value;
  int rows() const { return static_cast<int>(row_start.size()) - 1; }
};

class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  virtual std::size_t size() const = 0;
  virtual StateSegments segments() const = 0;
  virtual void rhs(double t, const double* y, double* ydot) = 0;
  virtual StabilitySnapshot stability() const = 0;
  // Implicit-explicit integrators (arkode-imex, docs/theory.md "Implicit-explicit
  // integration"): f = f_E + f_I, where f_I (implicit_part) is linear in the values from
  // segments().velocity_begin on (velocities, evolving fields) at frozen positions and
  // densities, and has no position or density rates. part == full is rhs(). A system that
  // declares no split has f_I = 0: everything explicit.
  // implicit_diagonal writes the diagonal of f_I's Jacobian (velocity and evolving-field rows;
  // zero elsewhere) instead of f_I.
  virtual void rhsPart(RhsPart part, double t, const double* y, double* ydot) {
    if (part != RhsPart::full && part != RhsPart::explicit_part) {
      for (std::size_t k = 0, n = size(); k < n; ++k) ydot[k] = 0.0;
      return;
    }
    rhs(t, y, ydot);
  }
  // The stability inputs of the explicit part f_E alone, at its last evaluation: the limits of
  // terms in f_I (viscous, relaxation) are absent. Same as stability() without a split.
  virtual StabilitySnapshot explicitStability() const { return stability(); }
  // The velocity block of f_I's Jacobian when it is one scalar operator L shared by every
  // velocity component (d f_I,v_i / d v_j = L_ij I for moving particles i, j; a fixed
  // neighbour's share on the diagonal), at y: the matrix of the assembled preconditioner of the
  // implicit stage solves (docs/theory.md §9.5). Returns false when the implicit part has no
  // such coupling (the preconditioner then stays diagonal).
  virtual bool implicitVelocityOperator(double t, const double* y, CsrMatrix& L) { return false; }
  // Called after each accepted step with the new state; returns false to stop the run.
  virtual bool afterStep(double t, double dt, double* y) = 0;
  // Whether afterStep may change the state (a post-step projection): the fixed-step
  // integrators then evaluate the right-hand side again at the changed state.
  virtual bool afterStepChangesState() const { return false; }
  // Particle-count changes between steps (inflow, outflow). mayResize: the state's length may
  // change during the run (ARKODE then returns after every step). After afterStep returned
  // true, an integrator asks resizePending(); if so it calls resizeState, which rewrites the
  // state for the new particle set, possibly into a new buffer, and returns the buffer to go on
  // with; size() and segments() then describe it. The integrator restarts from it as after a
  // projection: the fixed-step ones evaluate the right-hand side again, ARKODE resizes
  // (ERKStepResize) and sets its vector tolerances again.
  virtual bool mayResize() const { return false; }
  // A run across processes: the state is this process's part of a vector distributed over the
  // MPI communicator this points to (an MPI_Comm), and norms and dot products must span every
  // part (ARKODE's error control: the MPIPlusX vector). Null in a serial run.
  virtual const void* stateCommunicator() const { return nullptr; }
  virtual bool resizePending() const { return false; }
  virtual double* resizeState(double t, double* y) { return y; }
  // A resize that only moves particles between the processes of a distributed run keeps every
  // particle and its rates: the fixed-step integrators then carry their rate vector across it
  // (stashRates before resizeState, takeRates after, both in the state's layout) instead of
  // evaluating again, so that the run follows the serial one (the leapfrog's carried rate is not
  // the rate at the state: src/time/leapfrog.cpp).
  virtual bool resizeKeepsRates() const { return false; }
  virtual void stashRates(const double* rate) {}
  virtual void takeRates(double* rate) const {}
};

struct IntegratorStats {
  std::uint64_t steps = 0;
  std::uint64_t rejected_steps = 0;
  std::uint64_t rhs_evals = 0;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  virtual std::string name() const = 0;
  // y must stay alive and hold the state for the life of the integration.
  virtual void start(OdeSystem& system, double t0, double* y) = 0;
  // Advances until t == tout exactly. Returns false if afterStep stopped the run early.
  virtual bool advance(double tout) = 0;
  virtual double time() const = 0;
  virtual double lastStep() const = 0;
  virtual IntegratorStats stats() const = 0;
  // Nominal order of accuracy (for convergence studies and tests).
  virtual int order() const = 0;
  // What the integrator carries from one step to the next besides the state (checkpoints,
  // `vesph run --resume`): the fixed-step integrators' rate F^n, which comes from the last
  // evaluation of the previous step (the leapfrog's corrector, at rho^{n+1/2}) and is not a
  // function of y^n alone. restoreCarried, called right after start, replaces what start
  // computed; a vector of the wrong size is ignored (start's own value stays). ARKODE carries
  // nothing: a resumed segment starts with a fresh step-size estimate.
  virtual std::vector<double> carried() const { return {}; }
  virtual void restoreCarried(const std::vector<double>& values) {}
  // The stability limits at the last evaluation, as this integrator applies them (all infinite
  // when it applies none: a fixed integrator.step). The run's step floor names the one that
  // collapsed the step.
  virtual StepLimits limits() const { return {}; }
};

// The explicit Butcher tables of SUNDIALS 6.4.1 (integrator.table), by name without the
// ARKODE_ prefix, with their order q and embedding order p (0: no embedding).
struct ButcherTableInfo {
  std::string name;
  int id;
  int order, embedding_order, stages;
};
const std::vector<ButcherTableInfo>& erkTables();

// The additive (IMEX) Runge-Kutta pairs of SUNDIALS 6.4.1 for arkode-imex (integrator.table):
// the pair's name, its explicit and implicit tables (without the ARKODE_ prefix), order q,
// embedding order p and stages.
struct ArkPairInfo {
  std::string name, explicit_table, implicit_table;
  int order, embedding_order, stages;
};
const std::vector<ArkPairInfo>& arkPairs();

}  // namespace vesph
