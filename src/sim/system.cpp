#include "vesph/sim/system.hpp"

#include <unordered_map>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <exception>
#include <stdexcept>

namespace vesph {

template <int D>
void SphSystem<D>::setup(double spacing, double rest_density, double viscosity, double skin) {
  body_acceleration_.setZero();
  pressure_model_ = nullptr;
  for (auto& e : effects) {
    body_acceleration_ += e->bodyAcceleration();
    if (const PressureModel* m = e->pressureModel()) {
      if (pressure_model_)
        throw InputError("two effects provide the pressure (" + std::string(e->name()) +
                         " and another); keep one");
      pressure_model_ = m;
    }
  }
  evolving_.clear();
  // Effects are set up in phase order, so that an effect finds the fields of the phases that
  // run before it (the velocity gradient before the stress model, the stress before its
  // divergence), whatever the order of the scene; inside a phase by passOrder (readers of a
  // value written in the same pass after its writer).
  std::stable_sort(effects.begin(), effects.end(), [](const auto& a, const auto& b) {
    return a->phase() != b->phase() ? a->phase() < b->phase() : a->passOrder() < b->passOrder();
  });
  std::vector<Effect<D>*> all;
  for (auto& e : effects) all.push_back(e.get());
  Setup<D> s{particles, kernel, spacing, rest_density, viscosity, body_acceleration_, pressure_model_, &evolving_, &all};
  for (auto& hk : hooks) hk->setup(s);
  moving_boundaries_.clear();
  for (auto& b : boundaries) {
    b->setup(s);
    if (b->movesFixed()) moving_boundaries_.push_back(b.get());
  }
  for (auto& e : effects) e->setup(s);
  particles.resizeFields();
  for (auto& b : boundaries) b->fieldsAllocated(particles);
  for (auto& e : effects) e->fieldsAllocated(particles);
  effects_carry_ = std::any_of(effects.begin(), effects.end(), [](const auto& e) { return !e->carriedPerParticle().empty(); });
  for (Field* f : evolving_)
    if (f->range == Field::Range::fixed) throw std::logic_error("field " + f->name + " cannot evolve: it covers fixed particles only");
  field_rates_.assign(evolving_.size(), nullptr);

  full_.clear(); explicit_.clear(); implicit_.clear();
  stability_inputs_ = {};
  explicit_stability_inputs_ = {};
  for (auto& e : effects) {
    e->stability(stability_inputs_);
    full_.add(e.get());
    // The split of implicit-explicit integrators (docs/theory.md "Implicit-explicit
    // integration"): each effect declares its implicit term; the limits of implicit terms do
    // not bound the explicit step.
    const ImplicitPart implicit = e->implicitPart();
    if (implicit != ImplicitPart::all) {
      explicit_.add(e.get());
      const StabilityInputs before = explicit_stability_inputs_;
      e->stability(explicit_stability_inputs_);
      if (implicit == ImplicitPart::linear_rate) {
        explicit_stability_inputs_.relaxation_time = before.relaxation_time;
        explicit_stability_inputs_.elastic_wave_speed = before.elastic_wave_speed;
      }
    }
    if (implicit != ImplicitPart::none) implicit_.add(e.get());
    const bool pair_phase = e->phase() == Phase::gradients || e->phase() == Phase::forces;
    if (e->pairwise() != pair_phase)
      throw std::logic_error("effect " + std::string(e->name()) + " is in the wrong phase");
  }
  for (auto& hk : hooks) {
    hk->stability(stability_inputs_);
    hk->stability(explicit_stability_inputs_);
  }
  next_id_ = 0;
  for (std::uint64_t ident : particles.id) next_id_ = std::max(next_id_, ident + 1);
  neighbours.configure(domain, kernel.supportRadius(), skin);
  // Inflow buffers and moving walls move fixed particles: the list then watches their
  // displacement as well.
  neighbours.trackFixed(mayResize() || movesFixed());
  neighbours.update(particles, true);
  driver.prepare(neighbours);
}

namespace {
// Every array and field of `from` into `to` (its fields, created where missing, keep their
// addresses).
template <int D>
void copyParticles(const ParticleSet<D>& from, ParticleSet<D>& to) {
  for (const auto& f : from.fields.all()) {
    Field& g = to.fields.require(f->name, f->components, f->range);
    g = *f;
  }
  to.position = from.position;
  to.velocity = from.velocity;
  to.density = from.density;
  to.mass = from.mass;
  to.kind = from.kind;
  to.id = from.id;
  to.n_moving = from.n_moving;
  to.n_ghost_moving = from.n_ghost_moving;
  to.n_ghost_fixed = from.n_ghost_fixed;
  for (const auto& g : to.fields.all())  // a field `from` lacks: zeros over its range
    if (!from.fields.find(g->name)) {
      const std::size_t n = g->range == Field::Range::all ? to.size() : g->range == Field::Range::moving ? to.n_moving : to.nFixed();
      g->data.assign(n * static_cast<std::size_t>(g->components), 0.0);
    }
}
}  // namespace

template <int D>
void SphSystem<D>::distribute() {
  if (!distribution) return;
  for (auto& hk : hooks) {
    hk->setDistribution(distribution.get());
    hk->distributing(particles);
  }
  if (changesParticleSet() && !whole_scene_) {  // the first distribution only
    whole_scene_.emplace();
    copyParticles(particles, *whole_scene_);
  }
  distribution->distribute(particles);
  afterRedistribution();
}

template <int D>
void SphSystem<D>::takeWholeScene() {
  if (!whole_scene_) throw std::logic_error("SphSystem::takeWholeScene: the whole scene was not kept");
  distribution->removeHalo(particles);
  copyParticles(*whole_scene_, particles);  // into the same fields: effects hold pointers to them
  whole_scene_.reset();
  afterRedistribution();  // effects, boundaries, neighbours and hooks follow the whole set
}

// A distributed scene keeps no particle index anywhere (Simulation::distribute refuses what
// does), so the effects and boundaries only see a set of a new size.
template <int D>
void SphSystem<D>::afterRedistribution() {
  remap_.old_size = particles.size();
  remap_.old_moving = particles.n_moving;
  remap_.source.resize(particles.n_moving);
  for (std::size_t i = 0; i < particles.n_moving; ++i) remap_.source[i] = static_cast<Index>(i);
  remap_.released_ids.clear();
  for (auto& e : effects) e->resized(particles, remap_);
  for (auto& b : boundaries) b->resized(remap_);
  neighbours.update(particles, true);
  driver.prepare(neighbours);
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->redistributed(context);
}

// The state holds the moving particles this process owns (all of them in a serial run).
template <int D>
std::size_t SphSystem<D>::size() const {
  const std::size_t owned = particles.ownedMoving();
  std::size_t n = owned * (2 * D + 1);
  for (const Field* f : evolving_) n += owned * static_cast<std::size_t>(f->components);
  return n;
}

template <int D>
StateSegments SphSystem<D>::segments() const {
  const std::size_t n = particles.ownedMoving();
  return {0, n * D, n * (D + 1), n * (2 * D + 1)};
}

template <int D>
void SphSystem<D>::pack(double* y) const {
  const std::size_t n = particles.ownedMoving();
  std::memcpy(y, particles.position.data(), sizeof(double) * n * D);
  std::memcpy(y + n * D, particles.density.data(), sizeof(double) * n);
  std::memcpy(y + n * (D + 1), particles.velocity.data(), sizeof(double) * n * D);
  std::size_t off = n * (2 * D + 1);
  for (const Field* f : evolving_) {
    std::memcpy(y + off, f->data.data(), sizeof(double) * n * f->components);
    off += n * f->components;
  }
}

template <int D>
void SphSystem<D>::unpack(const double* y) {
  const std::size_t n = particles.ownedMoving();
  double* x = particles.position.data();
  double* rho = particles.density.data();
  double* v = particles.velocity.data();
  const double* y_rho = y + n * D;
  const double* y_v = y + n * (D + 1);
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < D; ++a) {
      x[D * i + a] = domain.wrap(a, y[D * i + a]);
      v[D * i + a] = y_v[D * i + a];
    }
    rho[i] = y_rho[i];
  }
  std::size_t off = n * (2 * D + 1);
  for (Field* f : evolving_) {
    std::memcpy(f->data.data(), y + off, sizeof(double) * n * f->components);
    off += n * f->components;
  }
}

template <int D>
void SphSystem<D>::particlePass(const std::vector<Effect<D>*>& list, const RhsContext<D>& ctx, std::size_t n) {
  if (list.empty()) return;
  // An exception must not leave an OpenMP region (that terminates the program): the first
  // one (a model's NumericalFailure) is kept and rethrown after the region.
  std::exception_ptr failure;
#pragma omp parallel if (n >= kParallelMinimum)
  {
    const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
    const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
    const std::size_t b = n * t / nt, e = n * (t + 1) / nt;
    try {
      for (Effect<D>* eff : list) eff->particles(ctx, b, e);
    } catch (...) {
#pragma omp critical(vesph_particle_pass_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
}

template <int D>
void SphSystem<D>::PhaseLists::add(Effect<D>* e) {
  switch (e->phase()) {
    case Phase::state: state.push_back(e); break;
    case Phase::gradients: gradients.push_back(e); break;
    case Phase::rates: rates.push_back(e); break;
    case Phase::forces: forces.push_back(e); break;
    case Phase::external: external.push_back(e); break;
  }
  if (Effect<D>* part = e->gradientsPart()) gradients.push_back(part);
}

template <int D>
void SphSystem<D>::rhs(double t, const double* y, double* ydot) {
  ++rhs_evals_;
  evaluate(t, y, ydot);
}

template <int D>
void SphSystem<D>::evaluate(double t, const double* y, double* ydot) {
  evaluateWith(full_, RhsPart::full, t, y, ydot);
}

template <int D>
void SphSystem<D>::rhsPart(RhsPart part, double t, const double* y, double* ydot) {
  ++rhs_evals_;
  switch (part) {
    case RhsPart::full: evaluateWith(full_, part, t, y, ydot); break;
    case RhsPart::explicit_part: evaluateWith(explicit_, part, t, y, ydot); break;
    case RhsPart::implicit_part:
    case RhsPart::implicit_diagonal: evaluateWith(implicit_, part, t, y, ydot); break;
  }
}

template <int D>
void SphSystem<D>::evaluateWith(const PhaseLists& lists, RhsPart part, double t, const double* y, double* ydot) {
  unpack(y);
  // A distributed run: the ghosts take their owners' state (docs/architecture.md "Distributed
  // runs"); after each phase below that writes values a later one reads from neighbours, the
  // ghosts take those too.
  refreshGhosts();
  placeFixed(t);  // moving walls at time t (before the list sees the positions)
  if (neighbours.update(particles)) driver.prepare(neighbours);

  const std::size_t n = particles.ownedMoving();
  double* dxdt = ydot;
  double* drhodt = ydot + n * D;
  double* dvdt = ydot + n * (D + 1);
  // The implicit part has no position rate: dx/dt = v is explicit.
  const double* v = particles.velocity.data();
  const bool implicit = part == RhsPart::implicit_part || part == RhsPart::implicit_diagonal;
  last_evaluation_implicit_ = implicit;
  const double position_rate = implicit ? 0.0 : 1.0;
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < D; ++a) {
      dxdt[D * i + a] = position_rate * v[D * i + a];
      dvdt[D * i + a] = 0.0;
    }
    drhodt[i] = 0.0;
  }
  std::size_t off = n * (2 * D + 1);
  for (std::size_t k = 0; k < evolving_.size(); ++k) {
    field_rates_[k] = ydot + off;
    std::memset(field_rates_[k], 0, sizeof(double) * n * evolving_[k]->components);
    off += n * evolving_[k]->components;
  }

  const RhsContext<D> ctx{particles, kernel, domain, t, dxdt, drhodt, dvdt, field_rates_.data(), part};
  // The state phase (the pressure from the density) is per particle and writes no rate: it runs
  // over the ghosts too, which saves a refresh.
  particlePass(lists.state, ctx, particles.n_moving);
  for (auto& b : boundaries) b->update(ctx, neighbours, driver);
  if (distribution && !boundaries.empty()) distribution->refreshFields(particles);
  driver.run(ctx, neighbours, lists.gradients);
  if (distribution && !lists.gradients.empty()) distribution->refreshFields(particles);
  particlePass(lists.rates, ctx, n);
  if (distribution && !lists.rates.empty()) distribution->refreshFields(particles);
  driver.run(ctx, neighbours, lists.forces);
  particlePass(lists.external, ctx, n);
  // The stability inputs come from full and explicit evaluations (the implicit part's
  // velocities are Krylov directions within a linear solve, not states).
  if (implicit) return;

  double vmax2 = 0, amax2 = 0;
#pragma omp parallel for reduction(max : vmax2, amax2) schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    double v2 = 0, a2 = 0;
    for (int a = 0; a < D; ++a) {
      v2 += dxdt[D * i + a] * dxdt[D * i + a];
      a2 += dvdt[D * i + a] * dvdt[D * i + a];
    }
    vmax2 = std::max(vmax2, v2);
    amax2 = std::max(amax2, a2);
  }
  if (distribution) {  // every process takes the same step
    vmax2 = distribution->max(vmax2);
    amax2 = distribution->max(amax2);
  }
  max_speed_ = std::sqrt(vmax2);
  (part == RhsPart::full ? max_acceleration_ : explicit_max_acceleration_) = std::sqrt(amax2);
}

template <int D>
bool SphSystem<D>::implicitVelocityOperator(double t, const double* y, CsrMatrix& L) {
  std::vector<Effect<D>*> coupling;
  for (const auto* list : {&implicit_.gradients, &implicit_.forces})
    for (Effect<D>* e : *list)
      if (e->couplesVelocities()) coupling.push_back(e);
  if (coupling.empty()) return false;
  unpack(y);
  refreshGhosts();
  placeFixed(t);
  if (neighbours.update(particles)) driver.prepare(neighbours);
  // The rows of the state's particles. In a run across processes the couplings to ghosts are
  // left out: the operator is this process's diagonal block (a block-Jacobi preconditioner of
  // arkode-imex's stage systems, whose Krylov solve spans every process).
  const std::size_t n = particles.ownedMoving();
  coupling_rows_.resize(n);
  const RhsContext<D> ctx{particles, kernel, domain, t, nullptr, nullptr, nullptr, field_rates_.data(), RhsPart::implicit_diagonal};
  wall_dependence_.assign(particles.nFixed(), 0.0);
  for (auto& b : boundaries) b->velocityDependence(particles, wall_dependence_);
  driver.forEachMoving(particles, kernel, domain, neighbours, false,
                       [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                         VelocityCouplingRow& row = coupling_rows_[i];
                         row.diagonal = 0;
                         row.entries.clear();
                         for (Effect<D>* e : coupling) e->velocityCoupling(ctx, i, moving, fixed, wall_dependence_, row);
                       });
  L.row_start.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    auto& entries = coupling_rows_[i].entries;
    if (distribution)
      std::erase_if(entries, [n](const auto& e) { return static_cast<std::size_t>(e.first) >= n; });
    L.row_start[i + 1] = L.row_start[i] + 1 + static_cast<int>(entries.size());
  }
  L.column.resize(static_cast<std::size_t>(L.row_start[n]));
  L.value.resize(L.column.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t k = static_cast<std::size_t>(L.row_start[i]);
    L.column[k] = static_cast<int>(i);
    L.value[k] = coupling_rows_[i].diagonal;
    for (const auto& [j, c] : coupling_rows_[i].entries) {
      ++k;
      L.column[k] = static_cast<int>(j);
      L.value[k] = c;
    }
  }
  return true;
}

template <int D>
StabilitySnapshot SphSystem<D>::stability() const {
  StabilitySnapshot s;
  s.h = kernel.h;
  s.sound_speed = stability_inputs_.sound_speed;
  s.elastic_wave_speed = stability_inputs_.elastic_wave_speed;
  s.relaxation_time = stability_inputs_.relaxation_time;
  s.kinematic_viscosity = stability_inputs_.kinematic_viscosity;
  s.max_speed = max_speed_;
  s.max_acceleration = max_acceleration_;
  return s;
}

template <int D>
StabilitySnapshot SphSystem<D>::explicitStability() const {
  StabilitySnapshot s = stability();
  s.elastic_wave_speed = explicit_stability_inputs_.elastic_wave_speed;
  s.relaxation_time = explicit_stability_inputs_.relaxation_time;
  s.kinematic_viscosity = explicit_stability_inputs_.kinematic_viscosity;
  s.sound_speed = explicit_stability_inputs_.sound_speed;
  s.max_acceleration = explicit_max_acceleration_;
  return s;
}

template <int D>
StepContext<D>& SphSystem<D>::stepContext() {
  context_.emplace(particles, domain, kernel, neighbours, driver, *this, effects, hooks, body_acceleration_);
  return *context_;
}

template <int D>
void SphSystem<D>::startHooks(double t, double* y) {
  placeFixed(t);
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->start(context, t, y);
}

template <int D>
bool SphSystem<D>::afterStep(double t, double dt, double* y) {
  placeFixed(t);  // the hooks (the ISPH projection) see the moving walls at the step's time
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->apply(context, t, dt, y);
  const std::size_t n = particles.ownedMoving();
  const AcceptedStep<D> step{t, dt, n, y, y + n * D, y + n * (D + 1)};
  for (auto& e : effects) e->afterStep(step);
  if (distribution) {
    // Values that effects carry per particle from step to step (the lagged second-order
    // fluid's acceleration) were just written on the owned particles: the ghosts take them.
    if (effects_carry_) distribution->refreshFields(particles);
    unpack(y);
    const RedistributionNeed need =
        distribution->needsRedistribution(particles, max_speed_ * dt, anyHook(&StepHook<D>::pendingChanges));
    redistribute_pending_ = need.redistribute;
    particle_changes_anywhere_ = need.particle_changes;
  }
  return true;
}

template <int D>
double* SphSystem<D>::resizeState(double, double*) {
  throw std::logic_error("SphSystem::resizeState: a system whose particle count changes is integrated through "
                         "IntegratedSystem (the run's state owns the resize)");
}

template <int D>
bool SphSystem<D>::resizeKeepsRates() const {
  // A serial run evaluates again after its hooks' changes: so does every process then.
  return distribution && redistribute_pending_ && !particle_changes_anywhere_;
}

template <int D>
std::vector<std::size_t> SphSystem<D>::segmentWidths() const {
  std::vector<std::size_t> widths{D, 1, D};
  for (const Field* f : evolving_) widths.push_back(static_cast<std::size_t>(f->components));
  return widths;
}

template <int D>
bool SphSystem<D>::changesParticleSet() const {
  return anyHook(&StepHook<D>::changesParticles);
}

// The rates of the owned moving particles, in the state's layout, into the field
// "carried_rate" (one row of the state's per-particle values each), and back.
template <int D>
void SphSystem<D>::stashRates(const double* rate) {
  const std::vector<std::size_t> widths = segmentWidths();
  std::size_t width = 0;
  for (std::size_t w : widths) width += w;
  Field& carried = particles.fields.require("carried_rate", static_cast<int>(width), Field::Range::moving);
  carried.refreshed_in_halo = false;
  carried.data.assign(particles.n_moving * width, 0.0);
  forEachStateValue(particles.ownedMoving(), widths,
                    [&](std::size_t k, std::size_t i, std::size_t col) { carried.at(i)[col] = rate[k]; });
}

template <int D>
void SphSystem<D>::takeRates(double* rate) const {
  const Field* carried = particles.fields.find("carried_rate");
  if (!carried) throw std::logic_error("SphSystem::takeRates without stashRates");
  forEachStateValue(particles.ownedMoving(), segmentWidths(),
                    [&](std::size_t k, std::size_t i, std::size_t col) { rate[k] = carried->at(i)[col]; });
}

template <int D>
bool SphSystem<D>::afterStepChangesState() const {
  return anyHook(&StepHook<D>::changesState);
}

template <int D>
bool SphSystem<D>::mayResize() const {
  return distribution != nullptr || anyHook(&StepHook<D>::changesParticles);
}

template <int D>
bool SphSystem<D>::resizePending() const {
  if (distribution) return redistribute_pending_;  // every process's answer (afterStep)
  return anyHook(&StepHook<D>::pendingChanges);
}

template <int D>
void SphSystem<D>::rearrangeParticles(const double* y) {
  unpack(y);  // the particle set holds the accepted (and post-processed) state
  if (distribution) {  // the hooks' changes, then the particles go to their owners, the halo is built again
    if (particle_changes_anywhere_) changeParticlesAcrossProcesses();
    distribution->redistribute(particles);
    redistribute_pending_ = particle_changes_anywhere_ = false;
    afterRedistribution();
    return;
  }
  changes_.remove.clear();
  changes_.release.clear();
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->collectChanges(context, changes_);
  std::vector<std::uint64_t> released_ids(changes_.release.size());
  for (std::uint64_t& ident : released_ids) ident = next_id_++;
  applyChanges(released_ids);
}

template <int D>
void SphSystem<D>::changeParticlesAcrossProcesses() {
  changes_.remove.clear();
  changes_.release.clear();
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->collectChanges(context, changes_);
  // The changes name particles of the set with its halo: the owned moving ones keep their
  // places without it, the owned fixed ones move up by the ghost moving ones.
  const std::size_t ghost_moving = particles.n_ghost_moving;
  distribution->removeHalo(particles);
  for (Index& b : changes_.release) b -= static_cast<Index>(ghost_moving);
  // A serial run numbers the particles a step releases in the order of their buffer particles'
  // ids (the buffer's order): every process's releases, in that order, take the next ids.
  std::vector<double> mine;
  for (Index b : changes_.release) mine.push_back(static_cast<double>(particles.id[b]));
  std::vector<double> all = distribution->allGather(mine);
  std::sort(all.begin(), all.end());
  std::vector<std::uint64_t> released_ids;
  for (double source : mine) {
    const auto place = std::lower_bound(all.begin(), all.end(), source) - all.begin();
    released_ids.push_back(next_id_ + static_cast<std::uint64_t>(place));
  }
  next_id_ += all.size();
  applyChanges(released_ids);
}

template <int D>
void SphSystem<D>::applyChanges(const std::vector<std::uint64_t>& released_ids) {
  const std::size_t n = particles.n_moving;
  removed_flag_.assign(n, 0);
  for (Index i : changes_.remove) {
    if (i >= n) throw std::logic_error("a hook removes a fixed particle");
    removed_flag_[i] = 1;
  }
  remap_.old_size = particles.size();
  remap_.old_moving = n;
  remap_.source.clear();
  remap_.released_ids.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (!removed_flag_[i]) remap_.source.push_back(static_cast<Index>(i));
  for (std::size_t k = 0; k < changes_.release.size(); ++k) {
    const Index b = changes_.release[k];
    if (b < n || b >= particles.size()) throw std::logic_error("a hook releases a particle that is not fixed");
    remap_.source.push_back(b);
    remap_.released_ids.push_back(released_ids.at(k));
  }
  applyRemap();
}

template <int D>
void SphSystem<D>::rebuildMovingSet(const std::vector<std::uint64_t>& moving_ids) {
  const std::size_t n = particles.n_moving;
  if (particles.nFixed() == 0) throw std::logic_error("rebuildMovingSet needs a fixed particle to create from");
  std::unordered_map<std::uint64_t, Index> index_of;
  for (std::size_t i = 0; i < n; ++i) index_of.emplace(particles.id[i], static_cast<Index>(i));
  remap_.old_size = particles.size();
  remap_.old_moving = n;
  remap_.source.clear();
  remap_.released_ids.clear();
  for (std::uint64_t ident : moving_ids) {
    const auto it = index_of.find(ident);
    if (it != index_of.end()) {
      remap_.source.push_back(it->second);
    } else {
      remap_.source.push_back(static_cast<Index>(n));  // the first fixed particle's values
      remap_.released_ids.push_back(ident);
    }
  }
  applyRemap();
}

template <int D>
void SphSystem<D>::applyRemap() {
  particles.remapMoving(remap_);
  for (auto& e : effects) e->resized(particles, remap_);
  for (auto& b : boundaries) b->resized(remap_);
  StepContext<D>& context = stepContext();
  for (auto& hk : hooks) hk->resized(context, remap_);
  neighbours.update(particles, true);
  driver.prepare(neighbours);
}

template class SphSystem<2>;
template class SphSystem<3>;

}  // namespace vesph
