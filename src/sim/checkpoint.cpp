#include "vesph/sim/checkpoint.hpp"

#include "vesph/io/config.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <utility>

namespace vesph {

template <int D>
void Checkpoints<D>::join(std::string prefix, RestoreStage stage, Save save, Restore restore,
                          std::vector<PerParticleArray> per_particle) {
  Carrier c{std::move(prefix), stage, std::move(save), std::move(restore), {}};
  for (const PerParticleArray& a : per_particle) c.per_particle.push_back({arrayName(c, a.name), a.components});
  carriers_.push_back(std::move(c));
}

template <int D>
int Checkpoints<D>::particleLaidOut(const std::string& name) const {
  for (const Carrier& c : carriers_)
    for (const PerParticleArray& a : c.per_particle)
      if (a.name == name) return a.components;
  return 0;
}

template <int D>
void Checkpoints<D>::joinScene() {
  // Effects and hooks carry what their saveCarried writes (the lagged SOF acceleration, the
  // ISPH pressure, the inflow's totals). Hooks' arrays are those of the last step taken: after
  // a divergence (the checkpoint holds the last good state) the ISPH pressure is the failed
  // step's, which the first resumed step's right-hand side sees before its projection replaces
  // it.
  for (auto& e : system_.effects) {
    Effect<D>* effect = e.get();
    join(std::string(effect->name()), RestoreStage::scene,
         [effect](double, NamedArrays& out) { effect->saveCarried(out); },
         [effect](const ArrayLookup& find) { effect->restoreCarried(find); }, effect->carriedPerParticle());
  }
  if (system_.changesParticleSet())  // the particle set itself is part of the restart point
    join("", RestoreStage::particle_set, [this](double, NamedArrays& out) { saveParticleSet(out); },
         [this](const ArrayLookup& find) { restoreParticleSet(find); });
  for (auto& h : system_.hooks) {
    StepHook<D>* hook = h.get();
    join(std::string(hook->name()), RestoreStage::hooks_started,
         [hook](double, NamedArrays& out) { hook->saveCarried(out); },
         [hook](const ArrayLookup& find) { hook->restoreCarried(find); }, hook->carriedPerParticle());
  }
}

template <int D>
void Checkpoints<D>::joinIntegrator(Integrator& integrator) {
  // The integrator's carried rate belongs to the state it integrates: written only when the
  // frame is at the integrator's time (after a divergence the frame holds the last good state,
  // and nothing is carried then).
  join("integrator", RestoreStage::integrator_started,
       [&integrator](double t, NamedArrays& out) {
         std::vector<double> carried = integrator.carried();
         if (!carried.empty() && integrator.time() == t) out.emplace_back("carried", std::move(carried));
       },
       [&integrator](const ArrayLookup& find) {
         if (const std::vector<double>* carried = find("carried")) integrator.restoreCarried(*carried);
       });
}

template <int D>
Checkpoint Checkpoints<D>::at(double t, Checkpoint totals) const {
  Checkpoint c = std::move(totals);
  c.state = state_.values();
  c.id = system_.particles.id;
  NamedArrays own;
  for (const Carrier& carrier : carriers_) {
    own.clear();
    carrier.save(t, own);
    for (auto& [aname, values] : own) c.arrays.emplace_back(arrayName(carrier, aname), std::move(values));
  }
  return c;
}

namespace {
constexpr const char* kRowsPrefix = "checkpoint:";
// The carried array laid out as the state (the integrator's rate): it travels as rows.
constexpr const char* kStateLaidOut = "integrator.carried";
bool stateLaidOut(const std::string& name) { return name == kStateLaidOut; }
}  // namespace

template <int D>
void Checkpoints<D>::attachRows(ParticleSet<D>& owned, const Checkpoint& local) const {
  const std::vector<std::size_t> widths = system_.segmentWidths();
  std::size_t width = 0;
  for (std::size_t w : widths) width += w;
  const std::size_t n = system_.particles.ownedMoving();
  if (local.state.size() != n * width) throw std::logic_error("Checkpoints::attachRows: not this process's checkpoint");
  auto attach = [&](const std::string& name, const std::vector<double>& values) {
    if (values.size() != local.state.size())
      throw std::logic_error("checkpoint array " + name + " is not laid out as the state");
    Field& rows = owned.fields.require(kRowsPrefix + name, static_cast<int>(width), Field::Range::moving);
    rows.data.assign(owned.n_moving * width, 0.0);
    forEachStateValue(n, widths, [&](std::size_t k, std::size_t i, std::size_t col) { rows.at(i)[col] = values[k]; });
  };
  attach("state", local.state);
  for (const auto& [aname, values] : local.arrays)
    if (stateLaidOut(aname)) attach(aname, values);
  // Per-particle arrays: the owned particles' values (owned moving, then owned fixed: the order
  // of `owned`).
  const ParticleSet<D>& p = system_.particles;
  for (const auto& [aname, values] : local.arrays) {
    const int cols = particleLaidOut(aname);
    if (cols == 0) continue;
    const auto c = static_cast<std::ptrdiff_t>(cols);
    if (values.size() != p.size() * static_cast<std::size_t>(cols))
      throw std::logic_error("checkpoint array " + aname + " is not laid out per particle");
    Field& rows = owned.fields.require(kRowsPrefix + aname, cols, Field::Range::all);
    rows.data.assign(values.begin(), values.begin() + c * static_cast<std::ptrdiff_t>(p.ownedMoving()));
    rows.data.insert(rows.data.end(), values.begin() + c * static_cast<std::ptrdiff_t>(p.n_moving),
                     values.begin() + c * static_cast<std::ptrdiff_t>(p.ownedEnd()));
  }
}

template <int D>
CheckpointRows Checkpoints<D>::shareLayout(const OutputShare<D>& share) const {
  CheckpointRows rows{{share.moving_offset, share.moving_total, share.fixed_offset, share.fixed_total},
                      system_.segmentWidths(), {kStateLaidOut}, {}};
  if (system_.changesParticleSet())
    rows.particle_arrays = {{"particles.position", D}, {"particles.velocity", D}, {"particles.mass", 1}};
  for (const Carrier& c : carriers_)
    for (const PerParticleArray& a : c.per_particle)
      rows.particle_arrays.emplace_back(a.name, static_cast<std::size_t>(a.components));
  return rows;
}

template <int D>
Checkpoint Checkpoints<D>::shareCheckpoint(const OutputShare<D>& dealt, const Checkpoint& local) const {
  const ParticleSet<D>& share = dealt.particles;
  const std::vector<std::size_t> widths = system_.segmentWidths();
  auto detach = [&](const std::string& name) {
    const Field* rows = share.fields.find(kRowsPrefix + name);
    if (!rows) throw std::logic_error("Checkpoints::shareCheckpoint: no rows of " + name);
    std::vector<double> values(share.n_moving * static_cast<std::size_t>(rows->components));
    forEachStateValue(share.n_moving, widths, [&](std::size_t k, std::size_t i, std::size_t col) { values[k] = rows->at(i)[col]; });
    return values;
  };
  Checkpoint c;
  c.time = local.time;
  c.step = local.step;
  c.rhs_evals = local.rhs_evals;
  c.rejected_steps = local.rejected_steps;
  c.neighbour_builds = local.neighbour_builds;
  c.wall_seconds = local.wall_seconds;
  c.max_density_deviation = local.max_density_deviation;
  c.resumes = local.resumes;
  c.state = detach("state");
  c.id = share.id;
  // The arrays: the integrator's rate laid out as the state; a changing particle set's
  // per-particle arrays from the share's particles (the frame's rows); the rest (the particle
  // count, the next id, the hooks' totals) the same on every process.
  for (const auto& a : local.arrays) {
    const std::string& name = a.first;
    if (stateLaidOut(name)) c.arrays.emplace_back(name, detach(name));
    else if (particleLaidOut(name)) c.arrays.emplace_back(name, share.fields.find(kRowsPrefix + name)->data);
    else if (name == "particles.position") c.arrays.emplace_back(name, share.position);
    else if (name == "particles.velocity") c.arrays.emplace_back(name, share.velocity);
    else if (name == "particles.mass") c.arrays.emplace_back(name, share.mass);
    else if (name == "particles.n_moving")
      c.arrays.emplace_back(name, std::vector<double>{static_cast<double>(dealt.moving_total)});
    else c.arrays.push_back(a);
  }
  return c;
}

template <int D>
void Checkpoints<D>::restore(const Checkpoint& checkpoint, RestoreStage stage) const {
  for (const Carrier& carrier : carriers_)
    if (carrier.stage == stage)
      carrier.restore([&](const std::string& aname) { return checkpoint.find(arrayName(carrier, aname)); });
}

template <int D>
void Checkpoints<D>::saveParticleSet(NamedArrays& out) const {
  const ParticleSet<D>& p = system_.particles;
  out.emplace_back("particles.n_moving", std::vector<double>{static_cast<double>(p.n_moving)});
  out.emplace_back("particles.position", p.position);
  out.emplace_back("particles.velocity", p.velocity);
  out.emplace_back("particles.mass", p.mass);
  out.emplace_back("system.next_id", std::vector<double>{static_cast<double>(system_.nextId())});
}

// The moving set of the checkpoint (released particles in, removed ones out), the fixed
// particles' positions and velocities (the inflow buffer moves), the next id.
template <int D>
void Checkpoints<D>::restoreParticleSet(const ArrayLookup& find) {
  const Checkpoint& ck = *resuming_;
  const std::vector<double>* n_moving = find("particles.n_moving");
  // Without it, a checkpoint of a segment whose particle set could not change (written
  // before checks.leave_domain was switched to "remove"): the set must be the scene's own
  // (checked with every checkpoint).
  if (!n_moving) return;
  const std::vector<double>* position = find("particles.position");
  const std::vector<double>* velocity = find("particles.velocity");
  const std::vector<double>* mass = find("particles.mass");
  const std::vector<double>* next_id = find("system.next_id");
  if (n_moving->size() != 1 || !position || !velocity || !mass || !next_id || next_id->size() != 1)
    throw InputError("--resume: the checkpoint in " + where_ + " lacks part of the particle set of a scene whose particles change");
  // The fixed particles never change; their ids are checked with the whole set.
  const std::size_t nm = static_cast<std::size_t>((*n_moving)[0]);
  if (nm > ck.id.size() || ck.id.size() - nm != system_.particles.nFixed()) throw anotherParticleSet();
  system_.rebuildMovingSet(std::vector<std::uint64_t>(ck.id.begin(), ck.id.begin() + static_cast<std::ptrdiff_t>(nm)));
  ParticleSet<D>& p = system_.particles;
  if (position->size() != p.position.size() || velocity->size() != p.velocity.size() || mass->size() != p.mass.size())
    throw anotherParticleSet();
  p.position = *position;
  p.velocity = *velocity;
  p.mass = *mass;
  system_.setNextId(static_cast<std::uint64_t>((*next_id)[0]));
  state_.values().assign(system_.size(), 0.0);
}

template <int D>
InputError Checkpoints<D>::anotherParticleSet() const {
  const Checkpoint& ck = *resuming_;
  return InputError("--resume: the checkpoint in " + where_ + " belongs to another particle set (" +
                    std::to_string(ck.id.size()) + " particles, state of " + std::to_string(ck.state.size()) +
                    " values; the scene builds " + std::to_string(system_.particles.size()) + " and " +
                    std::to_string(state_.size()) + ")");
}

// What a resumed run starts from is checked before it is used (docs/user-guide.md "Resuming"):
// the checksum written with it (files of vesph versions before it carry none and are taken as
// they are), the time (within the run and that of one of the file's frames), every value finite.
template <int D>
void Checkpoints<D>::validate(const ResumeSource& src, const ResumeRules& rules) const {
  const Checkpoint& ck = src.checkpoint;
  auto refuse = [&](const std::string& what) { throw InputError("--resume: the checkpoint in " + where_ + " " + what); };
  if (ck.checksum && *ck.checksum != checkpointChecksum(ck))
    refuse("fails its checksum (the state, ids or carried arrays changed after they were written)");
  std::ostringstream t;
  t << ck.time;
  if (!(ck.time >= 0)) refuse("is at t = " + t.str() + " s, before the start of the run");
  if (!(ck.time < rules.end_time * (1 + 1e-12)))
    throw InputError("--resume: the checkpoint is at t = " + std::to_string(ck.time) + " s, beyond time.end = " +
                     std::to_string(rules.end_time) + " s; raise time.end to go on");
  const double tol = 1e-12 * std::max(1.0, std::abs(ck.time));
  if (std::none_of(src.frame_times.begin(), src.frame_times.end(),
                   [&](double ft) { return std::abs(ft - ck.time) <= tol; }))
    refuse("is at t = " + t.str() + " s, the time of none of the file's frames");
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  if (!finite(ck.state)) refuse("holds a non-finite state value");
  for (const auto& [aname, values] : ck.arrays)
    if (!finite(values)) refuse("holds a non-finite value in its array '" + aname + "'");
  std::vector<std::uint64_t> ids = ck.id;
  std::sort(ids.begin(), ids.end());
  if (std::adjacent_find(ids.begin(), ids.end()) != ids.end()) refuse("holds a particle id twice");
}

// The fluid particles' positions (the state's first D n_moving values): inside the domain along
// non-periodic axes (unless particles leaving it are removed), as the step checks keep them;
// along periodic axes the state holds them unwrapped (docs/architecture.md), so they are only
// bounded by how far a particle can have travelled: one period plus checks.max_speed * t.
template <int D>
void Checkpoints<D>::validatePositions(const Checkpoint& ck, const ResumeRules& rules) const {
  const Domain<D>& domain = system_.domain;
  std::size_t width = 0;
  for (std::size_t w : system_.segmentWidths()) width += w;
  // The checkpoint's moving particles (this process's share of them in a run across processes
  // is found later, by id).
  const std::size_t n = std::min(ck.state.size() / width, ck.id.size());
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < D; ++a) {
      const double x = ck.state[D * i + a];
      const double reach = domain.periodic[a] ? domain.length(a) + rules.max_speed * ck.time : 0.0;
      if (domain.periodic[a] || !rules.removes_leaving)
        if (!(x >= domain.lo[a] - reach && x <= domain.hi[a] + reach)) {
          std::ostringstream os;
          os << "--resume: the checkpoint in " << where_ << " places particle id " << ck.id[i] << " at " << "xyz"[a]
             << " = " << x << " m, outside the domain [" << domain.lo[a] << ", " << domain.hi[a] << "]"
             << (domain.periodic[a] ? " by more than one period and checks.max_speed * t" : "");
          throw InputError(os.str());
        }
    }
}

template <int D>
std::vector<double> Checkpoints<D>::byId(const Checkpoint& ck, const std::vector<double>& values, int components) const {
  std::unordered_map<std::uint64_t, std::size_t> row_of;
  row_of.reserve(ck.id.size());
  for (std::size_t j = 0; j < ck.id.size(); ++j) row_of.emplace(ck.id[j], j);
  const ParticleSet<D>& p = system_.particles;
  const auto cols = static_cast<std::size_t>(components);
  std::vector<double> part(p.size() * cols);
  bool found = values.size() == ck.id.size() * cols;
  for (std::size_t i = 0; i < p.size() && found; ++i) {
    const auto it = row_of.find(p.id[i]);
    found = it != row_of.end();
    if (found) std::copy_n(values.begin() + static_cast<std::ptrdiff_t>(cols * it->second), cols, part.begin() + static_cast<std::ptrdiff_t>(cols * i));
  }
  if (system_.distribution->sum(static_cast<std::uint64_t>(found ? 0 : 1)) != 0) throw anotherParticleSet();
  return part;
}

template <int D>
std::vector<double> Checkpoints<D>::ownedPart(const Checkpoint& ck, const std::vector<double>& values) const {
  const std::vector<std::size_t> widths = system_.segmentWidths();
  std::size_t width = 0;
  for (std::size_t w : widths) width += w;
  const std::size_t n_ck = ck.state.size() / width;
  std::unordered_map<std::uint64_t, std::size_t> row_of;
  row_of.reserve(n_ck);
  for (std::size_t j = 0; j < n_ck; ++j) row_of.emplace(ck.id[j], j);
  const ParticleSet<D>& p = system_.particles;
  const std::size_t n = p.ownedMoving();
  std::vector<std::size_t> rows(n);
  bool found = values.size() == ck.state.size();
  for (std::size_t i = 0; i < n && found; ++i) {
    const auto it = row_of.find(p.id[i]);
    found = it != row_of.end();
    if (found) rows[i] = it->second;
  }
  // Every process must learn that one of them misses a particle (they all throw).
  if (system_.distribution->sum(static_cast<std::uint64_t>(found ? 0 : 1)) != 0) throw anotherParticleSet();
  std::vector<double> part(n * width);
  std::size_t off_ck = 0, off = 0;
  for (std::size_t w : widths) {
    for (std::size_t i = 0; i < n; ++i)
      std::copy_n(values.begin() + static_cast<std::ptrdiff_t>(off_ck + w * rows[i]), w,
                  part.begin() + static_cast<std::ptrdiff_t>(off + w * i));
    off_ck += n_ck * w;
    off += n * w;
  }
  return part;
}

// Every process read the whole checkpoint; the scene's particles are distributed by their
// initial positions. Each process takes its owned moving particles' state by id; then the
// particles go to the processes that own their checkpointed positions (a redistribution, as
// between steps), and the state is packed over the new owned set. The integrator's rate is
// taken the same way, by id, once the particles are where they stay.
template <int D>
void Checkpoints<D>::resumeDistributed(Checkpoint& ck) {
  ParticleDistribution<D>& dist = *system_.distribution;
  const ParticleSet<D>& p = system_.particles;
  std::size_t width = 0;
  for (std::size_t w : system_.segmentWidths()) width += w;
  const std::uint64_t moving = dist.sum(static_cast<std::uint64_t>(p.ownedMoving()));
  const std::uint64_t all = dist.sum(static_cast<std::uint64_t>(p.ownedMoving() + p.ownedEnd() - p.n_moving));
  if (ck.state.size() != moving * width || ck.id.size() != all) throw anotherParticleSet();
  state_.values() = ownedPart(ck, ck.state);
  system_.rearrangeParticles(state_.data());
  state_.resize(system_.size());
  system_.pack(state_.data());
  takeLocalParts(ck);
  ck.state.clear();
}

template <int D>
void Checkpoints<D>::takeLocalParts(Checkpoint& ck) const {
  for (auto& [aname, values] : ck.arrays) {
    if (stateLaidOut(aname)) values = ownedPart(ck, values);
    else if (const int cols = particleLaidOut(aname)) values = byId(ck, values, cols);
  }
}

template <int D>
Checkpoint Checkpoints<D>::resume(const std::string& dir, const ResumeRules& rules) {
  ResumeSource src = readResumeSource(dir, rules.scene_name);
  where_ = dir + "/" + rules.scene_name + ".h5";
  const std::string diff =
      firstSceneDifference(src.scene_toml, rules.resolved_scene, {"time", "output", "checks", "integrator"});
  if (!diff.empty())
    throw InputError("--resume: the scene differs from the one " + where_ + " was written with at '" + diff +
                     "'; only [time], [output], [checks] and [integrator] may change between the segments of a run");
  Checkpoint& ck = src.checkpoint;
  // The particle set's restore reads the checkpoint's ids and names the file (messages), while
  // this function runs.
  resuming_ = &ck;
  struct ClearOnExit {
    const Checkpoint*& slot;
    ~ClearOnExit() { slot = nullptr; }
  } clear_on_exit{resuming_};
  validate(src, rules);
  // A distributed scene whose particle set changes: the checkpoint's particle set is restored
  // into the whole scene, as serially, and then distributed (resumeWhole).
  const bool whole = system_.distribution && system_.hasWholeScene();
  if (system_.distribution && !whole) {
    validatePositions(ck, rules);
    resumeDistributed(ck);
    restore(ck, RestoreStage::scene);
    return std::move(src.checkpoint);
  }
  if (whole) {
    system_.takeWholeScene();
    state_.resize(system_.size());
  }
  restore(ck, RestoreStage::particle_set);
  if (ck.find("domain_exit.escaped") && !rules.removes_leaving)
    throw InputError("--resume: the run in " + where_ + " removes particles that leave the domain; "
                     "checks.leave_domain cannot go back to \"stop\" (its diagnostics column would end)");
  if (ck.id != system_.particles.id || ck.state.size() != state_.size()) throw anotherParticleSet();
  validatePositions(ck, rules);
  // Between-step arrays of effects (the lagged SOF acceleration) go back where they were.
  restore(ck, RestoreStage::scene);
  if (whole) {
    state_.values() = ck.state;
    system_.unpack(state_.data());
    system_.distribute();  // the restored set shared out again
    state_.resize(system_.size());
    system_.pack(state_.data());
    takeLocalParts(ck);
    ck.state.clear();
    return std::move(src.checkpoint);
  }
  state_.values() = std::move(ck.state);
  system_.unpack(state_.data());
  return std::move(src.checkpoint);
}

template class Checkpoints<2>;
template class Checkpoints<3>;

}  // namespace vesph
