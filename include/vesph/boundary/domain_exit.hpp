#pragma once
// Particles that leave the domain ([checks] leave_domain = "remove"): after each accepted step
// every fluid particle outside the domain box along a non-periodic axis is removed (a post-step
// hook; the removal is made between steps like an outflow's, StepHook::collectChanges), and
// counted: diagnostics column `escaped` (running total), summary.json `escaped`. Without it
// (leave_domain = "stop", the default) such a particle stops the run as a numerical failure.
// For splashes: droplets that an impact throws off (the refined drop cases,
// docs/validation.md §10) would otherwise end the run when they cross the domain boundary.
// The domain box is then the region the study cares about; what leaves it is gone, and the
// count says how much.
#include <cstdint>
#include <vector>

#include "vesph/physics/step_hook.hpp"

namespace vesph {

template <int D>
class DomainExit final : public StepHook<D> {
 public:
  std::string_view name() const override { return "domain_exit"; }
  bool distributable() const override { return true; }  // per owned particle; the count reduced
  void apply(StepContext<D>& system, double t, double dt, double* y) override;
  bool changesParticles() const override { return true; }
  bool pendingChanges() const override { return !remove_.empty(); }
  void collectChanges(const StepContext<D>& system, ParticleChanges& out) override;
  void resized(StepContext<D>& system, const ParticleRemap& remap) override;
  std::vector<std::string> diagnosticsColumns() const override { return {"escaped"}; }
  void diagnostics(std::vector<double>& values) const override;
  void summarize(nlohmann::json& summary) const override;
  std::string describe() const override;
  void saveCarried(NamedArrays& out) const override;
  void restoreCarried(const ArrayLookup& find) override;

 private:
  std::vector<Index> remove_;
  std::uint64_t escaped_ = 0;
};

}  // namespace vesph
