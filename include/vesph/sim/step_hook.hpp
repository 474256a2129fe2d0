#pragma once
// Post-step hooks (DESIGN.md "The shape": after each accepted step, hooks in order: ISPH
// projection, ...). A hook acts on the state an integrator has just accepted, between steps,
// never inside the right-hand side. A hook that changes the state (the ISPH projection) says
// so: the fixed-step integrators then evaluate the right-hand side again at the changed state
// before their next step, and ARKODE recomputes its first stage anyway (a post-process
// function is always registered, src/time/arkode.cpp).
#include <functional>
#include <string>
#include <utility>
#include <vector>
#include <string_view>

#include <nlohmann/json.hpp>

#include "vesph/io/output.hpp"
#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
class SphSystem;

// What the hooks ask of the particle set between two steps (inflow, outflow).
struct ParticleChanges {
  std::vector<Index> remove;   // moving particles to remove (outflow)
  std::vector<Index> release;  // fixed (buffer) particles to copy into the fluid (inflow)
};

template <int D>
class StepHook {
 public:
  virtual ~StepHook() = default;
  virtual std::string_view name() const = 0;
  // Runs before the effects are set up (Setup::find sees every effect of the scene).
  virtual void setup(Setup<D>& s) {}
  virtual bool changesState() const { return false; }
  // Once before the integration starts, at the initial state (the ISPH projection computes an
  // initial pressure).
  virtual void start(SphSystem<D>& system, double t, double* y) {}
  // y: the accepted state at time t, reached by a step of dt; the hook may change it.
  // Throws NumericalFailure when it cannot do its work (a failed linear solve).
  virtual void apply(SphSystem<D>& system, double t, double dt, double* y) = 0;
  // Particle-count changes (inflow, outflow; DESIGN.md "Particle count may change"). A hook that
  // may change the count says so at setup (changesParticles); after apply it says whether it
  // has changes for this step (pendingChanges). The integrator then, between steps, has the
  // system collect every hook's changes (collectChanges), rearrange the particles and the state
  // (ParticleRemap) and tell every hook (resized).
  virtual bool changesParticles() const { return false; }
  virtual bool pendingChanges() const { return false; }
  virtual void collectChanges(const SphSystem<D>& system, ParticleChanges& out) {}
  virtual void resized(SphSystem<D>& system, const ParticleRemap& remap) {}
  // What the hook carries between steps that neither the state nor the particle set holds
  // (checkpoints, `vesph run --resume`), as Effect::saveCarried / restoreCarried.
  virtual void saveCarried(NamedArrays& out) const {}
  virtual void restoreCarried(const ArrayLookup& find) {}
  // Per-step diagnostics columns of this hook (names fixed at setup) and their last values.
  virtual std::vector<std::string> diagnosticsColumns() const { return {}; }
  virtual void diagnostics(std::vector<double>& values) const {}
  // Totals for summary.json.
  virtual void summarize(nlohmann::json& summary) const {}
  // One or more "# ..." lines for `vesph run` / `vesph check`.
  virtual std::string describe() const { return {}; }
};

}  // namespace vesph
