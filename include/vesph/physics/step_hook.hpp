#pragma once
// Post-step hooks (docs/architecture.md "The life of one step": after each accepted step, the
// hooks in order: the ISPH projection, inflow/outflow, domain exit). A hook acts on the state an
// integrator has just accepted, between steps, never inside the right-hand side. A hook that
// changes the state (the ISPH projection) says so: the fixed-step integrators then evaluate the
// right-hand side again at the changed state before their next step, and ARKODE recomputes its
// first stage anyway (a post-process function is always registered, src/time/arkode.cpp).
//
// A hook sees the system through a StepContext: the particle set, the domain, the kernel, the
// neighbour structures and the pair driver, the state's unpacking and the right-hand side, and
// lookups of the scene's effects and hooks; not the system's other parts (its effect phases,
// boundaries, state bookkeeping). The names are those of SphSystem (sys.particles, sys.unpack(y),
// ...), so that a hook reads the same either way. This header sits beside the Effect interface
// (physics/), below sim/: boundaries (src/boundary) and the projection (src/isph) implement
// hooks without knowing the system that runs them.
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "vesph/core/distribution.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/physics/effect.hpp"
#include "vesph/physics/pair_driver.hpp"

namespace vesph {

// What the hooks ask of the particle set between two steps (inflow, outflow).
struct ParticleChanges {
  std::vector<Index> remove;   // moving particles to remove (outflow)
  std::vector<Index> release;  // fixed (buffer) particles to copy into the fluid (inflow)
};

// The state's unpacking and the right-hand side, as the system that runs the hooks provides
// them (SphSystem).
class StateEvaluator {
 public:
  // The length of the state vector.
  virtual std::size_t size() const = 0;
  // y into the particle set.
  virtual void unpack(const double* y) = 0;
  // The right-hand side at (t, y), not counted as an integrator's evaluation.
  virtual void evaluate(double t, const double* y, double* ydot) = 0;
  // Whether the last evaluation was of the implicit part alone (an implicit stage or a Jacobian
  // probe of an implicit-explicit integrator, whose velocities may be perturbed): the fields it
  // wrote (the velocity gradient) are then not those of an integrated state.
  virtual bool lastEvaluationImplicit() const = 0;
  // A run across processes: the ghosts take their owners' state as it was last unpacked
  // (positions, velocities, densities, evolving fields; nothing in a serial run). Collective.
  virtual void refreshGhosts() = 0;

 protected:
  ~StateEvaluator() = default;
};

template <int D>
class StepHook;

// What a hook may use of the system (header comment).
template <int D>
class StepContext {
 public:
  using Effects = std::vector<std::unique_ptr<Effect<D>>>;
  using Hooks = std::vector<std::unique_ptr<StepHook<D>>>;

  StepContext(ParticleSet<D>& particles_, const Domain<D>& domain_, const Kernel& kernel_,
              NeighbourList<D>& neighbours_, PairDriver<D>& driver_, StateEvaluator& state,
              const Effects& effects, const Hooks& hooks, const Vec<D>& body_acceleration)
      : particles(particles_), domain(domain_), kernel(kernel_), neighbours(neighbours_), driver(driver_),
        state_(state), effects_(effects), hooks_(hooks), body_acceleration_(body_acceleration) {}

  ParticleSet<D>& particles;
  const Domain<D>& domain;
  const Kernel& kernel;
  NeighbourList<D>& neighbours;
  PairDriver<D>& driver;

  std::size_t size() const { return state_.size(); }
  void unpack(const double* y) const { state_.unpack(y); }
  void evaluate(double t, const double* y, double* ydot) const { state_.evaluate(t, y, ydot); }
  bool lastEvaluationImplicit() const { return state_.lastEvaluationImplicit(); }
  void refreshGhosts() const { state_.refreshGhosts(); }
  // One effect's pass over the particle set as it is, at time t (a hook that needs a field of
  // the current state: the free-surface flags, the velocity gradient).
  void runEffect(Effect<D>* effect, double t) const {
    const RhsContext<D> ctx{particles, kernel, domain, t, nullptr, nullptr, nullptr, nullptr};
    driver.run(ctx, neighbours, std::span<Effect<D>* const>(&effect, 1));
  }
  Vec<D> bodyAcceleration() const { return body_acceleration_; }
  // The scene's effect of that name, or nullptr.
  Effect<D>* findEffect(std::string_view name) const {
    for (const auto& e : effects_)
      if (e->name() == name) return e.get();
    return nullptr;
  }
  // The first hook of type Hook, or nullptr (the projection asks for the inflow's direction).
  template <class Hook>
  const Hook* findHook() const {
    for (const auto& h : hooks_)
      if (const auto* found = dynamic_cast<const Hook*>(h.get())) return found;
    return nullptr;
  }

 private:
  StateEvaluator& state_;
  const Effects& effects_;
  const Hooks& hooks_;
  const Vec<D>& body_acceleration_;
};

template <int D>
class StepHook {
 public:
  virtual ~StepHook() = default;
  virtual std::string_view name() const = 0;
  // Runs before the effects are set up (Setup::find sees every effect of the scene).
  virtual void setup(Setup<D>& s) {}
  virtual bool changesState() const { return false; }
  // The step limits of the terms the hook applies explicitly (after setup; added to the
  // explicit part's limits as well as the full right-hand side's: a hook runs between steps,
  // outside any implicit solve).
  virtual void stability(StabilityInputs& in) const {}
  // Once before the integration starts, at the initial state (the ISPH projection computes an
  // initial pressure).
  virtual void start(StepContext<D>& system, double t, double* y) {}
  // y: the accepted state at time t, reached by a step of dt; the hook may change it.
  // Throws NumericalFailure when it cannot do its work (a failed linear solve).
  virtual void apply(StepContext<D>& system, double t, double dt, double* y) = 0;
  // Particle-count changes (inflow, outflow; docs/architecture.md "The life of one step"). A
  // hook that may change the count says so at setup (changesParticles); after apply it says
  // whether it has changes for this step (pendingChanges). The integrator then, between steps,
  // has the system collect every hook's changes (collectChanges), rearrange the particles and
  // the state (ParticleRemap) and tell every hook (resized).
  virtual bool changesParticles() const { return false; }
  virtual bool pendingChanges() const { return false; }
  virtual void collectChanges(const StepContext<D>& system, ParticleChanges& out) {}
  virtual void resized(StepContext<D>& system, const ParticleRemap& remap) {}
  // What the hook carries between steps that neither the state nor the particle set holds
  // (checkpoints, `vesph run --resume`; docs/architecture.md "Checkpoints"), as
  // Effect::saveCarried / restoreCarried.
  virtual void saveCarried(NamedArrays& out) const {}
  virtual void restoreCarried(const ArrayLookup& find) {}
  // The arrays of saveCarried that hold values per particle of the set, in its order (with the
  // halo in a run across processes): they travel with the particles (the ISPH pressure).
  virtual std::vector<PerParticleArray> carriedPerParticle() const { return {}; }
  // Per-step diagnostics columns of this hook (names fixed at setup) and their last values.
  // In a run across processes, the whole run's (every process calls it; collective).
  virtual std::vector<std::string> diagnosticsColumns() const { return {}; }
  virtual void diagnostics(std::vector<double>& values) const {}
  // Totals for summary.json (in a run across processes, the whole run's: collective).
  virtual void summarize(nlohmann::json& summary) const {}
  // One or more "# ..." lines for `vesph run` / `vesph check`.
  virtual std::string describe() const { return {}; }

  // Runs across processes (docs/architecture.md "Distributed runs"). A hook that can run
  // distributed says so; it then keeps no particle index across a redistribution: what it needs
  // per particle travels as fields of the set, put there when the whole scene is distributed
  // (distributing, before the first share is kept), and its index lists are rebuilt after
  // every (re)distribution (redistributed). Its changes (collectChanges) are indices into the
  // process's set with its halo; the system makes them on the owned particles. Its totals are
  // reduced over the processes through distribution().
  virtual bool distributable() const { return false; }
  virtual void distributing(ParticleSet<D>& whole) {}
  virtual void redistributed(StepContext<D>& system) {}
  // How many kernel supports deep the halo must be for this hook (1: what the pair loops need;
  // the ISPH projection eliminates the walls' pressures, which reach a support further, into
  // the fluid rows: 2).
  virtual int haloSupports() const { return 1; }
  void setDistribution(ParticleDistribution<D>* distribution) { distribution_ = distribution; }

 protected:
  ParticleDistribution<D>* distribution() const { return distribution_; }

 private:
  ParticleDistribution<D>* distribution_ = nullptr;
};

}  // namespace vesph
