#pragma once
// The SPH discretisation as an ODE right-hand side (docs/architecture.md "The life of one step"):
//   rhs(t, y, ydot): unpack y into the particle set -> neighbour search -> each active effect
//                    adds its contribution, phase by phase -> pack ydot
// The state vector holds the moving particles only: [positions n*D | densities n |
// velocities n*D | evolving fields]. Fixed particles (walls) live in the particle set and never
// enter it.
//
// The system does not own the state vector and knows nothing of the run: the run's OdeState
// owns y, and IntegratedSystem (vesph/sim/integrated_system.hpp) is what an integrator sees in a
// run. It calls afterStep (the hooks, then the effects' afterStep), then the run's StepObserver,
// and between steps rearrangeParticles followed by the state's repacking (docs/architecture.md
// "The life of one step"). A system with a fixed particle count can also be integrated by
// itself (unit tests).
#include <memory>
#include <optional>
#include <vector>

#include "vesph/boundary/boundary.hpp"
#include "vesph/core/distribution.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/physics/effect.hpp"
#include "vesph/physics/pair_driver.hpp"
#include "vesph/physics/step_hook.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

// fn(k, i, column) for every value of a state of n particles whose segments hold `widths`
// values per particle each (SphSystem::segmentWidths): k its place in the state vector, i its
// particle, column its place in the particle's row (the segments' values side by side). The
// carried rates' layout (SphSystem::stashRates) and a distributed checkpoint's
// (Checkpoints::attachRows).
template <class Fn>
void forEachStateValue(std::size_t n, const std::vector<std::size_t>& widths, Fn&& fn) {
  std::size_t off = 0, col = 0;
  for (std::size_t w : widths) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t c = 0; c < w; ++c) fn(off + w * i + c, i, col + c);
    off += n * w;
    col += w;
  }
}

template <int D>
class SphSystem final : public OdeSystem, public StateEvaluator {
 public:
  // The parts a scene is built from (and that unit tests build by hand).
  ParticleSet<D> particles;
  Domain<D> domain;
  Kernel kernel;
  NeighbourList<D> neighbours;
  PairDriver<D> driver;
  std::vector<std::unique_ptr<Effect<D>>> effects;
  std::vector<std::unique_ptr<Boundary<D>>> boundaries;
  // Run after every accepted step, in order, before the effects' afterStep (the ISPH
  // projection, src/isph; inflow/outflow and domain exit, src/boundary).
  std::vector<std::unique_ptr<StepHook<D>>> hooks;
  // A run across processes (docs/architecture.md "Distributed runs"); null in a serial run,
  // which then runs exactly as before. Set by the scene, which calls distribute() once.
  std::unique_ptr<ParticleDistribution<D>> distribution;

  // Sets up boundaries and effects (field requests, prerequisites) and sorts the effects
  // into their phases. Call once the particles exist.
  void setup(double spacing, double rest_density, double viscosity, double skin);
  // With a distribution: keeps this process's share of the whole scene built by every process,
  // with its halo, and rebuilds the neighbour list. Collective; after setup and before the
  // state is packed.
  void distribute();
  // A distributed scene whose particle set changes (inflow, outflow) keeps the whole scene as
  // built until the run starts: `--resume` restores a checkpoint into it (the particle set of
  // the checkpoint, as a serial run does) and distributes it again. takeWholeScene replaces
  // this process's share by it (no distribution afterwards until distribute());
  // releaseWholeScene frees it.
  bool hasWholeScene() const { return whole_scene_.has_value(); }
  void takeWholeScene();
  void releaseWholeScene() { whole_scene_.reset(); }

  std::size_t size() const override;
  StateSegments segments() const override;
  // The state's values per particle in each of its segments, in order: D positions, the
  // density, D velocities, then each evolving field's components.
  std::vector<std::size_t> segmentWidths() const;
  // Whether a hook adds or removes particles (the particle set is then part of a checkpoint).
  bool changesParticleSet() const;
  // The right-hand side as an integrator calls it (counted in rhsEvaluations).
  void rhs(double t, const double* y, double* ydot) override;
  // The same evaluation without counting it (derived fields for output, tests, hooks).
  void evaluate(double t, const double* y, double* ydot) override;
  bool lastEvaluationImplicit() const override { return last_evaluation_implicit_; }
  void refreshGhosts() override {
    if (distribution) distribution->refreshState(particles, evolving_);
  }
  StabilitySnapshot stability() const override;
  // One part of the right-hand side for implicit-explicit integrators (OdeSystem::rhsPart):
  // the explicit part runs every effect except those whose whole contribution is implicit
  // (Effect::implicitPart), the implicit part only the effects with an implicit term, after
  // the boundaries' wall values. Counted in rhsEvaluations. The full rhs is their sum.
  void rhsPart(RhsPart part, double t, const double* y, double* ydot) override;
  // The stability inputs without those of the implicit terms, at the last explicit evaluation.
  StabilitySnapshot explicitStability() const override;
  // The implicit part's scalar velocity coupling (OdeSystem::implicitVelocityOperator) from the
  // implicit effects that declare one (Effect::couplesVelocities): one neighbour pass.
  bool implicitVelocityOperator(double t, const double* y, CsrMatrix& L) override;

  // What the hooks see of the system (vesph/physics/step_hook.hpp). A system also converts to
  // it, so that code handing the system itself to a hook (tests: proj.apply(sys, ...)) reads as
  // before. Rebuilt on every call: it refers to this object's members.
  StepContext<D>& stepContext();
  operator StepContext<D>&() { return stepContext(); }
  // Once before the integration: every hook's start at the initial state.
  void startHooks(double t, double* y);
  // After an accepted step: the hooks in order (they may change y), then the effects'
  // afterStep. Always goes on (the run's checks are IntegratedSystem's).
  bool afterStep(double t, double dt, double* y) override;
  // Whether afterStep may change the state (a hook that does: the ISPH projection).
  bool afterStepChangesState() const override;
  // Whether the particle count may change during the run, and whether a hook asks for a change
  // after the last step.
  bool mayResize() const override;
  bool resizePending() const override;
  // The system does not own the state vector: a scene whose particle count changes is
  // integrated through IntegratedSystem (the run's OdeState resizes); here a logic error.
  double* resizeState(double t, double* y) override;
  // A distributed run's redistribution keeps the particles: the integrator's rates travel with
  // them (OdeSystem::resizeKeepsRates), through a moving-range field that the halo refresh
  // leaves out.
  bool resizeKeepsRates() const override;
  const void* stateCommunicator() const override { return distribution ? distribution->communicator() : nullptr; }
  void stashRates(const double* rate) override;
  void takeRates(double* rate) const override;
  // Between steps: y (the accepted, post-processed state) into the particle set, then every
  // hook's changes made (particles removed, buffer particles released), through one
  // ParticleRemap that the particle set, effects, boundaries, hooks and neighbour structures
  // follow. The state must then be packed again at the new size().
  void rearrangeParticles(const double* y);
  // Checkpoints of scenes whose particle set changes (`vesph run --resume`): the next id a
  // released particle gets, and the rebuild of the moving set as a checkpoint lists it. The
  // moving particles become those of `moving_ids`, in that order: a particle of the current
  // set keeps its values, any other is created (from a fixed particle's values, for the caller
  // to overwrite with the checkpoint's state) with that id, through the same remap as an
  // inflow release, so effects, boundaries and hooks follow (resized). The fixed particles
  // stay as they are.
  std::uint64_t nextId() const { return next_id_; }
  void setNextId(std::uint64_t id) { next_id_ = id; }
  void rebuildMovingSet(const std::vector<std::uint64_t>& moving_ids);

  void pack(double* y) const;
  void unpack(const double* y) override;
  // Whether a boundary moves fixed particles (moving walls).
  bool movesFixed() const { return !moving_boundaries_.empty(); }

  const PressureModel* pressureModel() const { return pressure_model_; }
  const std::vector<Field*>& evolvingFields() const { return evolving_; }
  Vec<D> bodyAcceleration() const { return body_acceleration_; }
  std::uint64_t rhsEvaluations() const { return rhs_evals_; }

 private:
  // The effects of each phase that one part of the right-hand side runs.
  struct PhaseLists {
    std::vector<Effect<D>*> state, gradients, rates, forces, external;
    void clear() { state.clear(); gradients.clear(); rates.clear(); forces.clear(); external.clear(); }
    void add(Effect<D>* e);
  };
  void evaluateWith(const PhaseLists& lists, RhsPart part, double t, const double* y, double* ydot);
  // The per-particle effects of a phase over the moving particles [0, n).
  void particlePass(const std::vector<Effect<D>*>& list, const RhsContext<D>& ctx, std::size_t n);
  // remap_ applied to the particle set, effects, boundaries, hooks and the neighbour structures.
  void applyRemap();
  // The hooks' changes (changes_, collected) as remap_, the released particles taking the ids
  // given (one per release, in order), then applied.
  void applyChanges(const std::vector<std::uint64_t>& released_ids);
  // A distributed run's hook changes: made on the owned particles (the halo removed), the
  // released particles numbered across the processes as a serial run numbers them.
  void changeParticlesAcrossProcesses();
  // After a distributed run's (re)distribution: effects, boundaries and the neighbour list
  // follow the new particle set.
  void afterRedistribution();

  // The boundaries that move fixed particles (Boundary::movesFixed): placed at the time of
  // every evaluation and of every accepted step.
  void placeFixed(double t) {
    for (Boundary<D>* b : moving_boundaries_) b->place(t, particles);
  }

  std::vector<Boundary<D>*> moving_boundaries_;
  PhaseLists full_, explicit_, implicit_;
  std::vector<VelocityCouplingRow> coupling_rows_;  // implicitVelocityOperator's rows, kept for their capacity
  std::vector<double> wall_dependence_;              // Boundary::velocityDependence
  std::vector<Field*> evolving_;
  std::vector<double*> field_rates_;
  StabilityInputs stability_inputs_;
  StabilityInputs explicit_stability_inputs_;  // without the implicit terms' inputs
  const PressureModel* pressure_model_ = nullptr;
  Vec<D> body_acceleration_ = Vec<D>::Zero();
  double max_speed_ = 0, max_acceleration_ = 0;
  double explicit_max_acceleration_ = 0;  // of the explicit part, at its last evaluation
  std::uint64_t rhs_evals_ = 0;
  bool last_evaluation_implicit_ = false;  // see StateEvaluator::lastEvaluationImplicit
  bool redistribute_pending_ = false;      // a distributed run's halo must be rebuilt before the next step
  bool effects_carry_ = false;             // some effect carries per-particle values between steps
  bool particle_changes_anywhere_ = false; // and some process's hooks add or remove particles
  std::uint64_t next_id_ = 0;
  std::optional<ParticleSet<D>> whole_scene_;  // see takeWholeScene
  ParticleChanges changes_;
  ParticleRemap remap_;
  std::vector<char> removed_flag_;
  std::optional<StepContext<D>> context_;
  // Whether some hook answers true (hook is a StepHook member predicate).
  template <class Pred>
  bool anyHook(Pred pred) const {
    for (const auto& hk : hooks)
      if (((*hk).*pred)()) return true;
    return false;
  }
};

}  // namespace vesph
