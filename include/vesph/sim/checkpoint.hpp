#pragma once
// Checkpoints (docs/architecture.md "Checkpoints"): every frame is a restart point for
// `vesph run --resume`: the run's totals, the state, the particle ids and the arrays carried
// between steps that neither the state nor the scene gives back. One registry lists who carries
// what; each carrier joins it once at setup, and the same list writes a checkpoint and restores
// one: each effect and each hook under its name ("<name>.<array>", Effect::saveCarried,
// StepHook::saveCarried), the particle set when the scene may change it ("particles.*",
// "system.next_id") and the integrator ("integrator.carried", Integrator::carried).
//
// Restoring goes in stages, each carrier at its own: the particle set first (the moving set is
// rebuilt as the checkpoint lists it), then the effects (their arrays follow the particle set),
// then, once the run has started them, the hooks (their start computes from the state alone what
// the checkpoint carries: the ISPH pressure, the hooks' totals) and the integrator (its rate
// F^n, replaced right after its start).
#include <functional>
#include <string>
#include <vector>

#include "vesph/io/output.hpp"
#include "vesph/physics/effect.hpp"
#include "vesph/sim/ode_state.hpp"
#include "vesph/sim/system.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

enum class RestoreStage { particle_set, scene, hooks_started, integrator_started };

// What a resumed scene must agree on with the checkpoint.
struct ResumeRules {
  std::string scene_name;      // names DIR/<name>.h5
  std::string resolved_scene;  // this segment's scene, compared with the file's
  double end_time = 0;
  bool removes_leaving = false;  // checks.leave_domain = "remove"
  double max_speed = 0;          // checks.max_speed, m/s: bounds how far a particle can have gone
};

template <int D>
class Checkpoints {
 public:
  // save: the carrier's arrays at a frame of time t; restore: from a checkpoint's arrays, found
  // by the carrier's own names.
  using Save = std::function<void(double t, NamedArrays& out)>;
  using Restore = std::function<void(const ArrayLookup& find)>;

  Checkpoints(SphSystem<D>& system, OdeState& state) : system_(system), state_(state) {}
  Checkpoints(const Checkpoints&) = delete;
  Checkpoints& operator=(const Checkpoints&) = delete;

  // One carrier: its arrays are written as "<prefix>.<name>" (an empty prefix: the names as
  // given), in the order the carriers joined.
  // per_particle: the carrier's arrays that hold values per particle of the set, in its order
  // (with the halo in a run across processes: Effect / StepHook::carriedPerParticle).
  void join(std::string prefix, RestoreStage stage, Save save, Restore restore,
            std::vector<PerParticleArray> per_particle = {});
  // The scene's carriers: the effects, the particle set when it may change, the hooks.
  void joinScene();
  void joinIntegrator(Integrator& integrator);

  // The restart point at a frame at time t of the current state: `totals` with the state, the
  // ids and every carrier's arrays.
  Checkpoint at(double t, Checkpoint totals) const;

  // A run across processes (docs/architecture.md "Distributed runs"): each process writes the
  // checkpoint rows of the particles it writes the frame of (ParticleDistribution::deal). The
  // values of `local` (this process's checkpoint, at()) travel with its owned particles as
  // fields of `owned` (attachRows); after the deal, the share's checkpoint is read back from
  // them (shareCheckpoint), its state and arrays in the state's layout over the share's moving
  // particles, its ids the share's.
  void attachRows(ParticleSet<D>& owned, const Checkpoint& local) const;
  Checkpoint shareCheckpoint(const OutputShare<D>& share, const Checkpoint& local) const;
  // Where the share's checkpoint values go in the file (OutputWriter::writeCheckpoint).
  CheckpointRows shareLayout(const OutputShare<D>& share) const;

  // --resume: the checkpoint in `dir` replaces the initial state (the state, the particle set,
  // the effects' arrays). Everything is checked before a file is touched: a refused resume is
  // invalid input (exit 2). Returns the checkpoint (its state moved into the OdeState) for the
  // later stages (restore) and the run's totals.
  Checkpoint resume(const std::string& dir, const ResumeRules& rules);
  // The carriers of one stage from a checkpoint.
  void restore(const Checkpoint& checkpoint, RestoreStage stage) const;

 private:
  struct Carrier {
    std::string prefix;
    RestoreStage stage;
    Save save;
    Restore restore;
    std::vector<PerParticleArray> per_particle;  // full array names
  };
  // The values per particle of a carried array that a Carrier lists in per_particle (0: none of
  // them): across processes it travels as the frame's rows and is taken back by id.
  int particleLaidOut(const std::string& name) const;
  // A per-particle array of the checkpoint (ck.id's order, `components` values each) for every
  // particle this process holds, its ghosts included, by id. Collective.
  std::vector<double> byId(const Checkpoint& ck, const std::vector<double>& values, int components) const;
  // A distributed resume, once the particles are where they stay: the checkpoint's arrays laid
  // out as the state (ownedPart) or per particle (byId) become this process's; the rest is the
  // same on every process and stays as written. Collective.
  void takeLocalParts(Checkpoint& ck) const;
  std::string arrayName(const Carrier& c, const std::string& name) const {
    return c.prefix.empty() ? name : c.prefix + "." + name;
  }
  void saveParticleSet(NamedArrays& out) const;
  void restoreParticleSet(const ArrayLookup& find);
  InputError anotherParticleSet() const;

  SphSystem<D>& system_;
  OdeState& state_;
  std::vector<Carrier> carriers_;
  // While resuming: the file and its checkpoint (for the particle set's checks and messages).
  void validate(const ResumeSource& src, const ResumeRules& rules) const;
  void validatePositions(const Checkpoint& ck, const ResumeRules& rules) const;
  // A distributed run's resume: the checkpoint (of any process count, or serial) holds every
  // particle; each process takes its owned particles' values by id, then the particles go to
  // the processes that own their positions.
  void resumeDistributed(Checkpoint& ck);
  // The values of a state-laid-out array of the checkpoint (all its moving particles) for this
  // process's owned moving particles, found by id.
  std::vector<double> ownedPart(const Checkpoint& ck, const std::vector<double>& values) const;
  std::string where_;
  const Checkpoint* resuming_ = nullptr;
};

}  // namespace vesph
