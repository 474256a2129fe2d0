// The ISPH projection hook; the method, its equations and references are in
// include/vesph/isph/projection.hpp and the files of its parts (src/isph/projection_parts.hpp).
#include "vesph/isph/projection.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "projection_parts.hpp"
#include "vesph/core/pair_loop.hpp"
#include "vesph/physics/constitutive.hpp"  // unpackSymmetric

namespace vesph {
namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

using isph::CarriedPressure;
using isph::GradientForm;
using isph::LaplacianForm;
using isph::WallCondition;

template <int D>
Projection<D>::Projection(ConfigTable& cfg, std::optional<Vec<D>> inflow_direction) {
  options_ = readLinearSolverOptions(cfg);
  laplacian_ = cfg.choice("laplacian", "consistent", {"consistent", "morris"}) == "consistent" ? LaplacianForm::consistent
                                                                                              : LaplacianForm::morris;
  const std::string g = cfg.choice("gradient", "renormalised", {"renormalised", "difference", "symmetric"});
  gradient_ = g == "renormalised" ? GradientForm::renormalised : g == "difference" ? GradientForm::difference : GradientForm::symmetric;
  // The choice between the carried pressure's forms; setup makes it none without
  // [effects.pressure_gradient].
  carried_ = cfg.choice("carried_pressure", "increment", {"increment", "predictor"}) == "predictor"
                 ? CarriedPressure::predictor
                 : CarriedPressure::increment;
  wall_condition_ = cfg.choice("wall_condition", "hydrostatic", {"hydrostatic", "no_penetration"}) == "no_penetration"
                        ? WallCondition::no_penetration
                        : WallCondition::hydrostatic;
  if (cfg.choice("inlet_condition", "zero_gradient", {"zero_gradient", "velocity"}) == "velocity") {
    if (!inflow_direction) cfg.fail("inlet_condition", "only with a prescribed [inflow] (the condition is the buffer's)");
    velocity_inlet_ = isph::VelocityInlet<D>{*inflow_direction};
  }
  surface_stress_.on = cfg.choice("surface_pressure", "zero", {"zero", "normal_stress"}) == "normal_stress";
  if (cfg.has("density_relaxation_time"))
    density_relaxation_time_ = cfg.number("density_relaxation_time", std::nullopt, Bound::positive, "s");
  if (cfg.boolean("divergence_cleaning", false)) {
    // Direct solvers only: the matrix is near-singular (divergence_cleaning.cpp), and conjugate
    // gradients did not reach 1e-8 in 5000 iterations on the 1520 unknowns of the hydrostatic
    // tank.
    cleaning_options_.type = cfg.choice("cleaning_solver", "umfpack", {"umfpack", "klu"});
    cleaning_ = std::make_unique<isph::DivergenceCleaning<D>>(cleaning_options_);
    if (density_relaxation_time_ > 0)
      cfg.fail("density_relaxation_time", "absent with divergence_cleaning = true (the exact projection would remove "
                                          "the divergence the relaxation asks for)");
  } else {
    if (cfg.has("cleaning_solver")) cfg.fail("cleaning_solver", "only with divergence_cleaning = true");
  }
  solver_ = makeLinearSolver(options_);
}

template <int D>
Projection<D>::~Projection() = default;

template <int D>
void Projection<D>::setup(Setup<D>& s) {
  struct Forbidden {
    const char* effect;
    const char* why;
  };
  for (const Forbidden& f :
       {Forbidden{"equation_of_state", "ISPH takes the pressure from the Poisson equation, not from an equation of state"},
        Forbidden{"continuity", "ISPH particles keep their density (the projection keeps the velocity divergence-free)"}})
    if (s.find(f.effect))
      throw InputError(std::string("effects.") + f.effect + ": not with solver.scheme = \"isph\" (" + f.why +
                       "); remove it, or use scheme = \"wcsph\"");
  pressure_ = &s.particles.fields.require("pressure", 1, Field::Range::all);
  // The free-surface detection the projection runs itself (its flag field is requested by the
  // effect's own setup, after the hooks'; flagFreeSurface binds it).
  free_surface_.effect = s.find("free_surface");
  // With [effects.pressure_gradient] the right-hand side carries the last projection's
  // pressure through the step, and the projection corrects it (incremental form, header).
  if (!s.find("pressure_gradient")) {
    if (carried_ == CarriedPressure::predictor)
      throw InputError("solver.carried_pressure = \"predictor\" needs [effects.pressure_gradient] (the pressure the "
                       "right-hand side carries); without it every projection solves for the whole pressure anyway");
    carried_ = CarriedPressure::none;
  }
  // The Neumann data of the velocity inlet and of no_penetration walls push the fluid within
  // one step; the increment form would carry that push on.
  if (velocity_inlet_ && carried_ == CarriedPressure::increment)
    throw InputError("solver.inlet_condition = \"velocity\" is not implemented with the incremental form "
                     "(carried_pressure = \"increment\"): the inlet's push would be carried on into the next steps; use "
                     "carried_pressure = \"predictor\" (docs/theory.md §10)");
  if (wall_condition_ == WallCondition::no_penetration && carried_ == CarriedPressure::increment)
    throw InputError("solver.wall_condition = \"no_penetration\" is not implemented with the incremental form "
                     "(carried_pressure = \"increment\"): the push would be carried on into the next steps; use "
                     "carried_pressure = \"predictor\" (docs/theory.md §10)");
  if (surface_stress_.on) {
    if (!free_surface_.effect)
      throw InputError("solver.surface_pressure = \"normal_stress\" needs [effects.free_surface] (its flags and "
                       "outward normals)");
    surface_stress_.gradient_effect = s.find("velocity_gradient");
    if (!surface_stress_.gradient_effect)
      throw InputError("solver.surface_pressure = \"normal_stress\" needs the velocity gradient of the viscous "
                       "stress: add [effects.velocity_gradient]");
    if (carried_ == CarriedPressure::increment)
      throw InputError("solver.surface_pressure = \"normal_stress\" is not implemented with the incremental form "
                       "(carried_pressure = \"increment\", whose Dirichlet value is the increment); use "
                       "carried_pressure = \"predictor\" or no [effects.pressure_gradient]");
    surface_stress_.viscosity = s.viscosity;
    surface_stress_.kinematic_viscosity = s.viscosity / s.rest_density;
    // Requested before the free-surface effect's own setup, which then fills it.
    surface_stress_.normal = &s.particles.fields.require("surface_normal", D, Field::Range::moving);
  }
  if (density_relaxation_time_ > 0) {
    if (!free_surface_.effect)
      throw InputError("solver.density_relaxation_time needs [effects.free_surface] (its number density is the "
                       "particles' spacing the term relaxes)");
    lattice_number_density_ = s.kernel.latticeSum(s.spacing);
  }
  unknowns_ = std::make_unique<isph::PressureUnknowns>();
  gradient_rows_ = std::make_unique<isph::GradientRows<D>>();
  walls_ = std::make_unique<isph::WallConditions<D>>(wall_condition_, velocity_inlet_, s.rest_density, s.body_acceleration);
  system_ = std::make_unique<isph::PressureSystem<D>>(s.rest_density);
  pressure_matrix_ = std::make_unique<isph::AssembledMatrix>();
}

template <int D>
void Projection<D>::flagFreeSurface(StepContext<D>& sys, double t) {
  if (!free_surface_.effect) return;
  if (!free_surface_.flag) free_surface_.flag = sys.particles.fields.find("free_surface");
  sys.runEffect(free_surface_.effect, t);
  // The ghosts' flags, normals and number densities from their owners (the surface values and
  // the unknowns' numbering read them).
  if (this->distribution()) this->distribution()->refreshFields(sys.particles);
}

template <int D>
void Projection<D>::refreshVelocities(StepContext<D>& sys) {
  if (!this->distribution()) return;
  const HaloArray v{sys.particles.velocity.data(), D, Field::Range::all};
  this->distribution()->refreshArrays(std::span<const HaloArray>(&v, 1));
}

template <int D>
SolveReport Projection<D>::solvePressure(Eigen::VectorXd& x) {
  if (unknowns_->global_count == 0) return SolveReport{true, 0, 0.0, {}};
  if (this->distribution())
    return solver_->solveAcross(pressure_matrix_->matrix, pressure_matrix_->pattern_changed, unknowns_->across,
                                system_->rhs(), x);
  return solver_->solve(pressure_matrix_->matrix, pressure_matrix_->pattern_changed, system_->rhs(), x);
}

template <int D>
void Projection<D>::distributing(ParticleSet<D>&) {
  // What the projection does not yet do across processes (issue 36), refused before the run.
  std::string missing;
  if (!solver_->solvesAcrossProcesses())
    missing = "solver.linear_solver = \"" + options_.type + "\" with preconditioner = \"" + options_.preconditioner +
              "\" (across processes the pressure is solved by hypre: linear_solver = \"bicgstab\", \"cg\" or "
              "\"gmres\" with preconditioner = \"amg\", the default)";
  else if (cleaning_)
    missing = "solver.divergence_cleaning (its exact operator reaches two supports through the gradient rows)";
  if (!missing.empty())
    throw InputError("a run across processes does not support yet (issue 36): " + missing + ". Run it as one process.");
  walls_->setDistribution(this->distribution());
}

template <int D>
void Projection<D>::numberUnknowns(const StepContext<D>& sys) {
  unknowns_->number(sys.particles, free_surface_.flag ? free_surface_.flag->data.data() : nullptr, this->distribution());
}

template <int D>
void Projection<D>::surfacePressures(StepContext<D>& sys, double t) {
  SurfaceNormalStress& ss = surface_stress_;
  // kappa: the field holds the last evaluation's, the one whose viscous traction the step
  // applied; when that was an implicit-only evaluation (an implicit stage or a Jacobian probe of
  // an implicit-explicit integrator, at a perturbed velocity: the gradient is shared with the
  // implicit part when the stress form or a linear stress rate is implicit), kappa of the state
  // being projected instead.
  if (sys.lastEvaluationImplicit()) {
    sys.runEffect(ss.gradient_effect, t);
    if (this->distribution()) this->distribution()->refreshFields(sys.particles);
  }
  const ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.n_moving;
  if (!ss.velocity_gradient) {
    ss.velocity_gradient = P.fields.find("velocity_gradient");
    ss.elastic_stress = P.fields.find("elastic_stress");
    if (!ss.velocity_gradient) throw std::logic_error("isph projection: no velocity_gradient field");
  }
  surface_pressure_.assign(n, 0.0);
  const double* flag = free_surface_.flag->data.data();
  const double* normal = ss.normal->data.data();
  const double* kappa = ss.velocity_gradient->data.data();
  const double* S = ss.elastic_stress ? ss.elastic_stress->data.data() : nullptr;
  const bool full = ss.elastic_stress && ss.elastic_stress->components == D * D;
  const double mu = ss.viscosity;
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  using Tensor = Eigen::Matrix<double, D, D>;
  // T_j = mu (kappa_j + kappa_j^T) + S_j (kappa row-major D x D; S packed symmetric, or the
  // second-order fluid's full tensor, whose n.S.n is that of its symmetric part).
  auto stress = [&](std::size_t j) {
    const Tensor k = loadStress<D>(kappa, true, j);
    Tensor T = mu * (k + k.transpose());
    if (S) T += loadStress<D>(S, full, j);
    return T;
  };
  // The surface value from the Shepard average of T over the particle's fluid neighbours (itself
  // included): the velocity gradient of the outermost rows, whose supports the surface cuts,
  // is the least accurate, and their own n.T.n alone let surface particles be thrown out of the
  // die's extrudate (docs/notes/die_swell.md, session 9).
  const CandidatePairs<D> pairs(P, sys.kernel, sys.domain, sys.neighbours);
  const NeighbourList<D>& list = sys.neighbours;
  sys.kernel.visit([&](auto shape) {
    const double w_self = sys.kernel.w_scale * decltype(shape)::f(0.0);
#pragma omp parallel for schedule(dynamic, 64) if (n >= kParallelMinimum)
    for (std::size_t i = 0; i < n; ++i) {
      if (!(flag[i] > 0.5)) continue;
      const Eigen::Map<const Vec<D>> nv(normal + D * i);
      double weight = w_self * m[i] / rho[i];
      Tensor T = weight * stress(i);
      pairs.visit(shape, i, list.start[i], list.start[i + 1],
                  [&](std::size_t, std::size_t j, const Vec<D>&, double W, double) {
                    if (j >= n) return;
                    const double w = W * m[j] / rho[j];
                    T += w * stress(j);
                    weight += w;
                  });
      surface_pressure_[i] = nv.dot((T / weight) * nv);
    }
  });
}

template <int D>
void Projection<D>::correctPositions(StepContext<D>& sys, double dt, double* y) {
  ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.ownedMoving();  // the state's particles
  const double half_dt2 = 0.5 * dt * dt;
  // y starts with the positions (SphSystem::pack)
  for (std::size_t k = 0; k < n * D; ++k) {
    y[k] -= half_dt2 * correction_[k];
    P.position[k] = sys.domain.wrap(static_cast<int>(k % D), y[k]);
  }
}

template <int D>
void Projection<D>::storePressure(const StepContext<D>& sys) {
  // Fluid: the solution on the unknowns, 0 on the free surface (and the pinned particle);
  // walls: the extrapolation p_w = sum_f c_wf p_f + b_w (src/isph/wall_conditions.cpp).
  // Across processes the ghost fluid particles take their owners' values before the walls
  // extrapolate (every wall particle here within a support of an owned one has its whole
  // neighbourhood in the halo, two supports deep: haloSupports).
  const std::size_t n = sys.particles.n_moving, N = sys.particles.size();
  double* p = pressure_->data.data();
  for (std::size_t i = 0; i < n; ++i) p[i] = surface_pressure_.empty() ? 0.0 : surface_pressure_[i];
  for (std::size_t r = 0; r < unknowns_->count; ++r) p[unknowns_->particle_of[r]] = solution_[static_cast<Eigen::Index>(r)];
  if (this->distribution()) {
    const HaloArray pressures{p, 1, Field::Range::all};
    this->distribution()->refreshArrays(std::span<const HaloArray>(&pressures, 1));
  }
  const NeighbourList<D>& list = sys.neighbours;
  const std::vector<double>& weight = walls_->weights();
  const std::vector<double>& offset = walls_->offsets();
  for (std::size_t w = n; w < N; ++w) {
    double pw = offset[w - n];
    for (std::size_t k = list.start[w]; k < list.split[w]; ++k) pw += weight[k] * p[list.nbr[k]];
    p[w] = pw;
  }
}

template <int D>
void Projection<D>::start(StepContext<D>& sys, double t, double* y) {
  solver_->prepare();
  surface_pressure_.clear();  // the initial solve: p = 0 on the surface (no velocity gradient yet)
  if (carried_ == CarriedPressure::none) return;
  const auto t0 = Clock::now();
  ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.ownedMoving();  // the state's particles
  // The pressure-free acceleration of the initial state (the pressure field is zero).
  std::vector<double> rate(sys.size());
  sys.evaluate(t, y, rate.data());
  const double* dvdt = rate.data() + n * (D + 1);
  // The projection of that acceleration, as a velocity over dt = 1, without the correction.
  for (std::size_t k = 0; k < n * D; ++k) P.velocity[k] = dvdt[k];
  refreshVelocities(sys);
  flagFreeSurface(sys, t);
  numberUnknowns(sys);
  // As in the plain form (there is no previous pressure whose wall offsets would cancel the
  // hydrostatic ones); with no_penetration the "velocity" is the acceleration over dt = 1 here,
  // against which the gaps, in metres, are negligible. No velocity inlet data: P.velocity holds
  // an acceleration.
  walls_->prepare(sys, 1.0, isph::SolvedFor::pressure, nullptr, divergence_);
  gradient_rows_->build(sys, gradient_, isph::WallPressures::enter);
  system_->assemble(sys, 1.0, laplacian_, *unknowns_, *gradient_rows_, *walls_, divergence_, pressure_->data.data(),
                    *pressure_matrix_);
  solution_.setZero(static_cast<Eigen::Index>(unknowns_->count));
  const auto t1 = Clock::now();
  const SolveReport rep = solvePressure(solution_);
  if (!rep.ok) fail("ISPH initial pressure solve failed: " + rep.message);
  initial_ = InitialSolve{static_cast<std::size_t>(unknowns_->global_count), rep.iterations, rep.residual, seconds(t0, t1),
                          seconds(t1, Clock::now())};
  storePressure(sys);
  sys.unpack(y);  // the velocities back
  sys.refreshGhosts();
}

template <int D>
void Projection<D>::fail(const std::string& message) const {
  // Across processes every process meets the same failed solve (its report is agreed on).
  if (this->distribution()) throw SharedNumericalFailure(message);
  throw NumericalFailure(message);
}

template <int D>
void Projection<D>::predictorStep(StepContext<D>& sys, double dt) {
  // The carried pressure only predicted the stages' pressure force: take its share out of v*
  // (v** = v* + dt G p^n) and solve for the whole pressure.
  const double* pn = pressure_->data.data();
  double* v = sys.particles.velocity.data();
  const std::size_t n = sys.particles.ownedMoving();
  const isph::GradientRows<D>& rows = *gradient_rows_;
  const NeighbourList<D>& list = sys.neighbours;
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t k = 0; k < n; ++k) {
    const Vec<D> a = rows.at(list, k, pn);
    for (int c = 0; c < D; ++c) v[D * k + c] += dt * a[c];
  }
  refreshVelocities(sys);
}

template <int D>
void Projection<D>::relaxDensity(StepContext<D>& sys, double dt) {
  // Density-invariant part of the source (Shao & Lo 2003; mixed with the divergence source as
  // Asai et al. 2012): the projected velocity's divergence is made (n_i/n_0 - 1)/tau instead
  // of zero, so that a particle packed closer than the lattice (n_i > n_0, the number
  // density at the positions the step reached) spreads and one spaced wider draws in, the
  // error relaxing over tau; a step longer than tau removes it at most once (fraction
  // min(1, dt/tau) per step). The rate is a time, not a fraction per step, so that the
  // correction's velocity does not grow as 1/dt under a tiny step (ARKODE's first). The
  // approximate projection alone keeps div v = 0 but lets the spacing drift
  // (docs/studies.md §5: the ISPH die packs 7-14 %).
  const double* nd = sys.particles.fields.find("number_density")->data.data();
  const double fraction = std::min(1.0, dt / density_relaxation_time_);
  const double rate = fraction / (lattice_number_density_ * dt), shift = fraction / dt;
  for (std::size_t i = 0; i < sys.particles.n_moving; ++i) divergence_[i] -= rate * nd[i] - shift;
}

template <int D>
void Projection<D>::apply(StepContext<D>& sys, double t, double dt, double* y) {
  const auto t0 = Clock::now();
  ParticleSet<D>& P = sys.particles;
  const std::size_t N = P.size();
  sys.unpack(y);
  sys.refreshGhosts();
  if (sys.neighbours.update(P)) sys.driver.prepare(sys.neighbours);
  flagFreeSurface(sys, t);
  numberUnknowns(sys);
  gradient_rows_->build(sys, gradient_, isph::WallPressures::enter);
  // The divergence of v* with the walls at rest (reported, and the source of the incremental
  // form; the wall conditions below compute the other forms' source).
  isph::continuityDivergence(sys, isph::WallFlux<D>{}, divergence_);
  last_.divergence_before = unknowns_->rms(divergence_, this->distribution());
  if (carried_ == CarriedPressure::predictor) predictorStep(sys, dt);
  const bool increment = carried_ == CarriedPressure::increment;
  walls_->prepare(sys, dt, increment ? isph::SolvedFor::increment : isph::SolvedFor::pressure, walls_->inlet(),
                  divergence_);
  if (density_relaxation_time_ > 0) relaxDensity(sys, dt);
  if (surface_stress_.on) surfacePressures(sys, t);
  system_->assemble(sys, dt, laplacian_, *unknowns_, *gradient_rows_, *walls_, divergence_,
                    increment ? pressure_->data.data() : nullptr, *pressure_matrix_,
                    surface_pressure_.empty() ? nullptr : surface_pressure_.data());
  // A closed domain (pinned pressure): the Neumann problem has a solution only when the
  // sources sum to zero; the discrete sources do not quite, and the pin would take the
  // remainder as a point source at one particle. Removing the mean spreads it evenly.
  Eigen::VectorXd& rhs = system_->rhs();
  if (unknowns_->pinned && unknowns_->global_count > 0) {
    double sum = rhs.sum();
    if (this->distribution()) sum = this->distribution()->sum(sum);
    rhs.array() -= sum / static_cast<double>(unknowns_->global_count);
  }
  const auto t1 = Clock::now();

  // Warm start (iterative solver): the previous pressure.
  double* p = pressure_->data.data();
  solution_.resize(static_cast<Eigen::Index>(unknowns_->count));
  for (std::size_t r = 0; r < unknowns_->count; ++r) solution_[static_cast<Eigen::Index>(r)] = p[unknowns_->particle_of[r]];
  last_.solve = solvePressure(solution_);
  const auto t2 = Clock::now();
  if (!last_.solve.ok) {
    std::ostringstream os;
    os << "ISPH pressure solve failed at t = " << t << " s (" << unknowns_->global_count << " unknowns): " << last_.solve.message;
    fail(os.str());
  }

  // The carried forms correct with the change of the pressure, p^{n+1} - p^n.
  const bool carried = carried_ != CarriedPressure::none;
  if (carried) previous_pressure_.assign(p, p + N);
  storePressure(sys);
  const isph::ProjectionOperators<D> ops{*unknowns_, *gradient_rows_, *system_, *walls_, divergence_, correction_};
  correction_.assign(P.n_moving * D, 0.0);
  isph::correctVelocities(sys, ops, dt, y, p, carried ? previous_pressure_.data() : nullptr);
  refreshVelocities(sys);
  // The corrected velocities' divergence at the positions of the solve: what the projection
  // acts on (the position correction that follows moves the operator by O(dt^2)).
  isph::continuityDivergence(sys, isph::WallFlux<D>{}, divergence_);
  last_.divergence_after = last_.divergence_projected = unknowns_->rms(divergence_, this->distribution());
  const auto t3 = Clock::now();
  if (cleaning_) cleaning_->apply(sys, ops, t, dt, y);
  const auto t4 = Clock::now();
  if (cleaning_) {
    isph::continuityDivergence(sys, isph::WallFlux<D>{}, divergence_);
    last_.divergence_after = unknowns_->rms(divergence_, this->distribution());
  }
  correctPositions(sys, dt, y);
  const auto t5 = Clock::now();

  last_.assembly_seconds = seconds(t0, t1);
  last_.cleaning_seconds = seconds(t3, t4);
  last_.solve_seconds = seconds(t1, t2);
  assembly_seconds_ += last_.assembly_seconds;
  solve_seconds_ += last_.solve_seconds;
  correction_seconds_ += seconds(t2, t3) + seconds(t4, t5);
  if (cleaning_) cleaning_->seconds += last_.cleaning_seconds;
  ++solves_;
  iterations_total_ += static_cast<std::uint64_t>(last_.solve.iterations);
  iterations_max_ = std::max(iterations_max_, last_.solve.iterations);
  residual_max_ = std::max(residual_max_, last_.solve.residual);
  if (last_.divergence_before > 0)
    divergence_ratio_max_ = std::max(divergence_ratio_max_, last_.divergence_after / last_.divergence_before);
}

template <int D>
const SolveReport& Projection<D>::lastCleaning() const {
  static const SolveReport none{};
  return cleaning_ ? cleaning_->last() : none;
}

template <int D>
std::size_t Projection<D>::unknowns() const {
  return unknowns_ ? static_cast<std::size_t>(unknowns_->global_count) : 0;
}

template <int D>
std::vector<std::string> Projection<D>::diagnosticsColumns() const {
  std::vector<std::string> c = {"solver_iterations", "solver_residual", "assembly_seconds", "solve_seconds",
                                "divergence_before", "divergence_after", "pressure_unknowns"};
  if (cleaning_) c.insert(c.end(), {"divergence_projected", "cleaning_iterations", "cleaning_residual", "cleaning_seconds"});
  return c;
}

template <int D>
void Projection<D>::diagnostics(std::vector<double>& v) const {
  v = {static_cast<double>(last_.solve.iterations), last_.solve.residual, last_.assembly_seconds, last_.solve_seconds,
       last_.divergence_before, last_.divergence_after, static_cast<double>(unknowns())};
  if (cleaning_)
    v.insert(v.end(), {last_.divergence_projected, static_cast<double>(cleaning_->last().iterations),
                       cleaning_->last().residual, last_.cleaning_seconds});
}

template <int D>
void Projection<D>::saveCarried(NamedArrays& out) const {
  out.emplace_back("pressure", pressure_->data);
  std::vector<double> totals{
      static_cast<double>(solves_), static_cast<double>(iterations_total_), static_cast<double>(iterations_max_),
      residual_max_, assembly_seconds_, solve_seconds_, correction_seconds_, divergence_ratio_max_,
      static_cast<double>(pressure_matrix_->pattern_builds),
      static_cast<double>(cleaning_ ? cleaning_->iterations_total : 0), static_cast<double>(cleaning_ ? cleaning_->iterations_max : 0),
      cleaning_ ? cleaning_->residual_max : 0.0, cleaning_ ? cleaning_->seconds : 0.0};
  // Across processes the totals are the same on every process (the checkpoint holds one copy):
  // the solver's are already; the times and pattern builds are each process's, their maximum.
  if (this->distribution()) this->distribution()->max(totals);
  out.emplace_back("totals", std::move(totals));
}

template <int D>
void Projection<D>::restoreCarried(const ArrayLookup& find) {
  const std::vector<double>* p = find("pressure");
  const std::vector<double>* t = find("totals");
  if (!p || !t || p->size() != pressure_->data.size() || t->size() != 13)
    throw InputError("--resume: the checkpoint lacks the ISPH pressure or solver totals (written by an older vesph?)");
  pressure_->data = *p;
  const auto count = [](double v) { return static_cast<std::uint64_t>(v); };
  solves_ = count((*t)[0]);
  iterations_total_ = count((*t)[1]);
  iterations_max_ = static_cast<int>((*t)[2]);
  residual_max_ = (*t)[3];
  assembly_seconds_ = (*t)[4];
  solve_seconds_ = (*t)[5];
  correction_seconds_ = (*t)[6];
  divergence_ratio_max_ = (*t)[7];
  pressure_matrix_->pattern_builds = count((*t)[8]);
  if (cleaning_) {
    cleaning_->iterations_total = count((*t)[9]);
    cleaning_->iterations_max = static_cast<int>((*t)[10]);
    cleaning_->residual_max = (*t)[11];
    cleaning_->seconds = (*t)[12];
  }
}

template <int D>
void Projection<D>::summarize(nlohmann::json& s) const {
  // Across processes: the slowest process's times and the most pattern builds (collective).
  double per_process[4] = {assembly_seconds_, solve_seconds_, correction_seconds_,
                           static_cast<double>(pressure_matrix_->pattern_builds)};
  if (this->distribution()) this->distribution()->max(per_process);
  const double assembly_seconds = per_process[0], solve_seconds = per_process[1], correction_seconds = per_process[2];
  const auto pattern_builds = static_cast<std::uint64_t>(per_process[3]);
  nlohmann::json j;
  j["linear_solver"] = solver_->name();
  j["solves"] = solves_;
  j["iterations_total"] = iterations_total_;
  j["iterations_max"] = iterations_max_;
  j["iterations_mean"] = solves_ ? static_cast<double>(iterations_total_) / static_cast<double>(solves_) : 0.0;
  j["max_relative_residual"] = residual_max_;
  j["assembly_seconds"] = assembly_seconds;
  j["solve_seconds"] = solve_seconds;
  j["correction_seconds"] = correction_seconds;
  j["seconds_per_solve"] = solves_ ? solve_seconds / static_cast<double>(solves_) : 0.0;
  j["pattern_builds"] = pattern_builds;
  j["max_divergence_ratio"] = divergence_ratio_max_;
  j["pressure_pinned"] = unknowns_->pinned;
  j["divergence_cleaning"] = cleaning_ != nullptr;
  if (initial_)
    j["initial_solve"] = {{"unknowns", initial_->unknowns},
                          {"iterations", initial_->iterations},
                          {"relative_residual", initial_->relative_residual},
                          {"assembly_seconds", initial_->assembly_seconds},
                          {"solve_seconds", initial_->solve_seconds}};
  if (cleaning_) {
    j["cleaning_iterations_total"] = cleaning_->iterations_total;
    j["cleaning_iterations_max"] = cleaning_->iterations_max;
    j["cleaning_max_relative_residual"] = cleaning_->residual_max;
    j["cleaning_seconds"] = cleaning_->seconds;
  }
  s["isph"] = j;
}

template <int D>
std::string Projection<D>::describe() const {
  std::ostringstream os;
  const char* grad = gradient_ == GradientForm::renormalised ? "renormalised difference form"
                     : gradient_ == GradientForm::difference ? "difference form (thesis 3.17)"
                                                         : "symmetric form (thesis 3.18)";
  os << "# ISPH projection after every step: Laplacian " << (laplacian_ == LaplacianForm::consistent ? "consistent (exact for linear fields)" : "thesis eq. (3.37) / Morris")
     << ", linear solver " << solver_->name() << ", pressure gradient " << grad << ";\n#   "
     << (free_surface_.effect ? (surface_stress_.on ? "p = n.T.n (the viscous and elastic normal stress) on the particles [effects.free_surface] flags"
                                                    : "p = 0 on the particles [effects.free_surface] flags")
                           : "no free-surface detection: p = 0 at one pinned fluid particle (closed or periodic domain)")
     << ";\n#   " << (carried_ == CarriedPressure::none ? "plain form (no pressure carried in the right-hand side)"
                      : carried_ == CarriedPressure::predictor ? "carried pressure as the stages' predictor, the whole pressure solved every step"
                                    : "incremental form (the pressure increment solved every step)")
     << "; walls " << (wall_condition_ == WallCondition::no_penetration ? "no_penetration (stop the approach closer than dx/2)" : "hydrostatic (Adami)") << "\n";
  if (velocity_inlet_)
    os << "#   inflow buffer as a velocity inlet: dp/dn = rho (u - u_w).e/dt there (inlet_condition = \"velocity\")\n";
  if (density_relaxation_time_ > 0)
    os << "#   density relaxation over " << density_relaxation_time_ << " s: the source targets div u = (n/n0 - 1)/tau (Shao & Lo 2003)\n";
  if (cleaning_)
    os << "#   then divergence cleaning: the exact projection onto discretely divergence-free velocities ("
       << cleaning_->solverName() << ")\n";
  return os.str();
}

template <int D>
std::unique_ptr<StepHook<D>> makeProjection(ConfigTable& solver_table, std::optional<Vec<D>> inflow_direction) {
  return std::make_unique<Projection<D>>(solver_table, inflow_direction);
}

template class Projection<2>;
template class Projection<3>;
template std::unique_ptr<StepHook<2>> makeProjection<2>(ConfigTable&, std::optional<Vec<2>>);
template std::unique_ptr<StepHook<3>> makeProjection<3>(ConfigTable&, std::optional<Vec<3>>);

}  // namespace vesph
