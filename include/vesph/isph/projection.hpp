#pragma once
// Incompressible SPH: the projection of thesis §3.5 (Cummins & Rudman 1999) as a post-step
// hook (docs/architecture.md "ISPH projection"; docs/theory.md §10). The right-hand side of an
// ISPH scene has no pressure: the integrator advances positions and velocities with the other
// forces (viscous, body, elastic) over a step dt to the intermediate velocity v*. After the
// accepted step this hook
//   1. flags the free surface at the accepted positions ([effects.free_surface], thesis §4.2);
//   2. solves for the pressure: p = 0 on free-surface particles (Dirichlet; with
//      solver.surface_pressure = "normal_stress" the normal part of the dynamic surface
//      condition, p_s = n.T.n, below), and on the other
//      fluid particles the pressure Poisson equation of thesis §3.5,
//          L p_i = -rho_i div(v*)_i / dt,
//      L the Laplacian of solver.laplacian (consistent or morris) and div the continuity
//      divergence (the equations: src/isph/pressure_system.cpp), with the walls' pressure
//      extrapolated from the fluid and eliminated into the fluid rows (solver.wall_condition,
//      hydrostatic or no_penetration, and solver.inlet_condition for an inflow buffer: the
//      Neumann data, src/isph/wall_conditions.cpp).
//      Incremental form (Goda 1979; van Kan 1986), when the scene lists
//      [effects.pressure_gradient]: the right-hand side then carries the last projection's
//      pressure p^n through the step (best with form = "renormalised", the gradient below), so
//      that the integrator's stages see the pressure force; the projection solves
//          L p^{n+1} = L p^n - rho_i div(v*)_i / dt
//      (the same operator, the same Dirichlet and wall conditions; the walls enter the source
//      at rest, since the hydrostatic wall offsets of p^{n+1} and p^n cancel) and corrects with
//      p^{n+1} - p^n in step 3. A fluid in equilibrium then stays exactly in equilibrium: without
//      it, the stages see v* = v + t g without the pressure that balances g, and the viscous
//      term of a no-slip wall acts on that spurious motion (a splitting error of O(nu dt / h^2)).
//      solver.carried_pressure = "predictor" keeps the carried pressure in the right-hand side
//      but solves each projection for the whole pressure: with v** = v* + dt G p^n (the stages'
//      pressure force taken out again, G at the step's end positions),
//          L p^{n+1} = -rho_i div(v**)_i / dt,   v^{n+1} = v** - dt G p^{n+1}
//      (the plain form's equation and walls; the correction is the same G (p^{n+1} - p^n) on v*).
//      Were L = rho div_h G the two would agree; for the approximate projection the increment
//      form keeps, step after step, whatever part of p^n the mismatch L - rho div_h G leaves
//      unanswered (pressure modes that G hardly moves) and the predictor form forgets it
//      (docs/theory.md §10 has what each does in the tank, a block impact and the drops).
//      The incremental form starts from the pressure that makes the initial acceleration
//      divergence-free (the same equation with v* the initial pressure-free acceleration and
//      dt = 1): a fluid that starts at rest under gravity starts with its hydrostatic pressure.
//      solver.density_relaxation_time = tau (Shao & Lo 2003, mixed as Asai et al. 2012)
//      subtracts f (n_i/n_0 - 1)/dt, f = min(1, dt/tau), from div(v*)_i (any form): the
//      corrected velocity's divergence is that target instead of zero, which spreads particles
//      packed closer than the lattice (n_i, the free-surface effect's number density; n_0 the
//      lattice's) over the time tau.
//   3. corrects velocities and positions of all fluid particles,
//          v_i = v*_i - dt (G p)_i,  x_i = x_i - dt^2/2 (G p)_i   (incremental: G (p^{n+1} - p^n)),
//      with G (solver.gradient) the renormalised difference form (default), thesis eq. (3.17)
//      or (3.18) (src/isph/pressure_system.cpp).
//      The position correction is the pressure acceleration's share of the step taken as
//      constant over it: a second-order integrator moved the particles by dt (v^n + v*)/2, so
//      the corrected positions are the thesis' x^{n+1} = x^n + dt (v^n + v^{n+1})/2.
//   4. (solver.divergence_cleaning) the exact projection of the corrected velocities onto the
//      discretely divergence-free fields (src/isph/divergence_cleaning.cpp).
// solver.surface_pressure = "normal_stress": on a free surface without surface tension the
// traction of the total stress vanishes, (-p I + T).n = 0 (thesis §4.2), whose normal part is
// p_s = n.T.n: for a viscous fluid 2 mu n.D.n, which near a die's lip, where the surface rows
// accelerate from the wall's rest (dv_n/dn < 0), is a suction of the order of the die's
// pressure. p = 0 there (the default, "zero") is the inviscid condition. T = mu (kappa +
// kappa^T) + S, Shepard-averaged over the particle's fluid neighbours (the outermost rows' own
// kappa is the least accurate): kappa the velocity gradient of the step's last right-hand side
// ([effects.velocity_gradient]), S the elastic stress of a viscoelastic model where the scene
// has one, n the free-surface detection's outward normal (docs/theory.md §10).
// Without free-surface detection (closed or periodic domains) the pressure is fixed by
// p = 0 at one fluid particle (the first), which makes the Neumann problem non-singular; the
// mean of the right-hand side is removed first (solvability of the Neumann problem).
//
// The modes are strategies chosen once, at construction and setup (src/isph/projection_parts.hpp):
// the Laplacian and gradient forms, the carried pressure (none, increment, predictor), the wall
// condition with the optional velocity inlet, and the cleaning as an optional stage. The
// combinations that are not implemented are refused there with the reason.
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/isph/linear_solver.hpp"
#include "vesph/physics/step_hook.hpp"

namespace vesph {

namespace isph {
// The strategies of the projection, chosen once (src/isph/projection_parts.hpp has the parts
// that carry them out).
// solver.laplacian: the operator of the pressure equation. exact is the divergence cleaning's
// (src/isph/divergence_cleaning.cpp), not a choice of the scene.
enum class LaplacianForm { consistent, morris, exact };
// solver.gradient: the gradient G of the correction.
enum class GradientForm { renormalised, difference, symmetric };
// What the right-hand side carries from one projection to the next (step 2, the incremental
// form): nothing (no [effects.pressure_gradient]: the plain form); the pressure, the
// projection solving for its increment (solver.carried_pressure = "increment"); or the
// pressure as the stages' predictor, the projection solving for the whole pressure
// (carried_pressure = "predictor").
enum class CarriedPressure { none, increment, predictor };
// solver.wall_condition: the walls' Neumann data (src/isph/wall_conditions.cpp).
enum class WallCondition { hydrostatic, no_penetration };
// The velocity inlet (solver.inlet_condition = "velocity"): the prescribed inflow buffer's
// direction e (a unit vector; the buffer's particles are those of kind inflow).
template <int D>
struct VelocityInlet {
  Vec<D> direction;
};

struct PressureUnknowns;
template <int D> struct GradientRows;
template <int D> class WallConditions;
template <int D> class PressureSystem;
template <int D> class DivergenceCleaning;
struct AssembledMatrix;
}  // namespace isph

template <int D>
class Projection final : public StepHook<D> {
 public:
  // solver_table: [solver] of an ISPH scene. inflow_direction: the prescribed inflow buffer's
  // flow direction e (a unit vector), where the scene has one (the velocity inlet's data).
  Projection(ConfigTable& solver_table, std::optional<Vec<D>> inflow_direction);
  ~Projection() override;

  std::string_view name() const override { return "isph_projection"; }
  void setup(Setup<D>& s) override;
  bool changesState() const override { return true; }
  // solver.surface_pressure = "normal_stress": p_s = n.T.n carries the viscous stress 2 mu
  // n.kappa.n, applied explicitly through the Dirichlet rows: its step limit is the viscous one,
  // also under an implicit-explicit integrator (docs/theory.md §10). Measured on the die at
  // Re = 0.5, 10 across, arkode-imex: the flux swell 1.179 at the viscous limit, 1.016 at twice it.
  void stability(StabilityInputs& in) const override {
    in.kinematic_viscosity = std::max(in.kinematic_viscosity, surface_stress_.kinematic_viscosity);
  }
  void start(StepContext<D>& sys, double t, double* y) override;
  void apply(StepContext<D>& sys, double t, double dt, double* y) override;
  // The incremental form keeps the last pressure per particle: it follows the particles when
  // an inflow or outflow changes the set (a released particle starts from its buffer
  // particle's pressure).
  void resized(StepContext<D>& sys, const ParticleRemap& remap) override {
    if (previous_pressure_.size() == remap.old_size) remap.apply(previous_pressure_, 1, Field::Range::all);
  }
  // Checkpoints keep the pressure field (the incremental form's p^n, the iterative solvers'
  // first guess) and the run's solver totals; on resume they replace what start() computed.
  void saveCarried(NamedArrays& out) const override;
  void restoreCarried(const ArrayLookup& find) override;
  std::vector<PerParticleArray> carriedPerParticle() const override { return {{"pressure", 1}}; }
  std::vector<std::string> diagnosticsColumns() const override;
  void diagnostics(std::vector<double>& values) const override;
  void summarize(nlohmann::json& summary) const override;
  std::string describe() const override;
  // Runs across processes (docs/architecture.md "Distributed runs"): the rows of the owned
  // fluid particles, the ghosts' unknowns as further columns, one hypre solve over every
  // process; the halo two supports deep, for the walls' pressures eliminated into the rows.
  // distributing refuses what is not distributed yet (the direct and Eigen solvers, the
  // divergence cleaning).
  bool distributable() const override { return true; }
  void distributing(ParticleSet<D>& whole) override;
  int haloSupports() const override { return 2; }

  // Root-mean-square of the discrete divergence (1/s) over the pressure unknowns, before and
  // after the last projection (the "after" value at the corrected positions).
  double divergenceBefore() const { return last_.divergence_before; }
  double divergenceAfter() const { return last_.divergence_after; }
  // With divergence cleaning: after the pressure projection, before the cleaning.
  double divergenceProjected() const { return last_.divergence_projected; }
  const SolveReport& lastCleaning() const;
  const SolveReport& lastSolve() const { return last_.solve; }
  std::size_t unknowns() const;

 private:
  struct LastProjection {
    SolveReport solve;
    double assembly_seconds = 0, solve_seconds = 0, divergence_before = 0, divergence_after = 0;
    double divergence_projected = 0, cleaning_seconds = 0;
  };
  // The free-surface detection the projection runs at the accepted positions (step 1): the
  // scene's [effects.free_surface], bound at setup, and its flag field.
  struct FreeSurfaceDetection {
    Effect<D>* effect = nullptr;
    const Field* flag = nullptr;
  };
  void flagFreeSurface(StepContext<D>& sys, double t);
  void numberUnknowns(const StepContext<D>& sys);
  // The assembled pressure equation solved into x (x: the first guess), serially or by every
  // process together over its rows.
  SolveReport solvePressure(Eigen::VectorXd& x);
  // The ghosts' velocities from their owners (after the owners' were changed; runs across
  // processes only).
  void refreshVelocities(StepContext<D>& sys);
  // A failed solve: NumericalFailure, shared by every process in a run across processes.
  [[noreturn]] void fail(const std::string& message) const;
  void predictorStep(StepContext<D>& sys, double dt);
  void relaxDensity(StepContext<D>& sys, double dt);
  void correctPositions(StepContext<D>& sys, double dt, double* y);
  void storePressure(const StepContext<D>& sys);
  // solver.surface_pressure = "normal_stress": p_s = n.T.n of every flagged particle into
  // surface_pressure_ (0 elsewhere), from the fields bound at the first call (the velocity
  // gradient recomputed at the state being projected, time t, when the last evaluation was of
  // the implicit part alone).
  void surfacePressures(StepContext<D>& sys, double t);

  // Configuration: the strategies, read from [solver] at construction; the carried pressure
  // is completed at setup (none without [effects.pressure_gradient]).
  LinearSolverOptions options_;
  isph::GradientForm gradient_ = isph::GradientForm::renormalised;
  isph::LaplacianForm laplacian_ = isph::LaplacianForm::consistent;
  isph::CarriedPressure carried_ = isph::CarriedPressure::increment;
  isph::WallCondition wall_condition_ = isph::WallCondition::hydrostatic;
  std::optional<isph::VelocityInlet<D>> velocity_inlet_;
  LinearSolverOptions cleaning_options_;  // solver.cleaning_solver, with divergence_cleaning
  // solver.density_relaxation_time (tau, s; 0: off) and the lattice's number density, 1/m^D,
  // against which the free-surface effect's number density at the step's positions is compared.
  double density_relaxation_time_ = 0, lattice_number_density_ = 1;

  // solver.surface_pressure = "normal_stress" (header): the fluid's viscosity mu (Pa s), the
  // fields it reads and the Dirichlet values per moving particle.
  struct SurfaceNormalStress {
    bool on = false;
    double viscosity = 0;
    double kinematic_viscosity = 0;  // mu/rho0: the step limit of the explicit p_s (stability)
    const Field* normal = nullptr;
    const Field* velocity_gradient = nullptr;
    const Field* elastic_stress = nullptr;  // null: no viscoelastic model
    Effect<D>* gradient_effect = nullptr;    // [effects.velocity_gradient], run on the projected state
  };
  SurfaceNormalStress surface_stress_;
  std::vector<double> surface_pressure_;

  // Set up.
  FreeSurfaceDetection free_surface_;
  Field* pressure_ = nullptr;
  std::unique_ptr<LinearSolver> solver_;
  std::unique_ptr<isph::PressureUnknowns> unknowns_;
  std::unique_ptr<isph::GradientRows<D>> gradient_rows_;
  std::unique_ptr<isph::WallConditions<D>> walls_;
  std::unique_ptr<isph::PressureSystem<D>> system_;
  std::unique_ptr<isph::AssembledMatrix> pressure_matrix_;
  std::unique_ptr<isph::DivergenceCleaning<D>> cleaning_;  // null: no cleaning stage

  // Per step.
  Eigen::VectorXd solution_;
  std::vector<double> previous_pressure_;
  std::vector<double> divergence_;  // per moving particle: div v*
  std::vector<double> correction_;  // per moving particle: the velocity correction / dt

  LastProjection last_;
  // The initial pressure solve (start): from a zero guess, unlike the steps' warm-started
  // solves, so its iterations measure the preconditioner (the benchmark's cold solve). Empty
  // on a resumed run, which starts from the checkpoint's pressure.
  struct InitialSolve {
    std::size_t unknowns = 0;
    int iterations = 0;
    double relative_residual = 0, assembly_seconds = 0, solve_seconds = 0;
  };
  std::optional<InitialSolve> initial_;
  std::uint64_t solves_ = 0, iterations_total_ = 0;
  int iterations_max_ = 0;
  double residual_max_ = 0, assembly_seconds_ = 0, solve_seconds_ = 0, correction_seconds_ = 0;
  double divergence_ratio_max_ = 0;
};

template <int D>
std::unique_ptr<StepHook<D>> makeProjection(ConfigTable& solver_table, std::optional<Vec<D>> inflow_direction);

}  // namespace vesph
