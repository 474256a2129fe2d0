// The weakly compressible scheme (docs/architecture.md "Pressure schemes"): the pressure comes
// from an equation of state, an effect of the scene ([effects.equation_of_state], thesis 3.5),
// so the scheme adds no hook; [solver] holds nothing else.
#include "vesph/sim/pressure_scheme.hpp"

namespace vesph {

template <int D>
class WcsphScheme final : public PressureScheme<D> {
 public:
  std::string_view name() const override { return "wcsph"; }
  void build(SchemeBuild<D>& scene) const override {
    for (const std::string& key : scene.solver.keys())
      if (key != "scheme")
        scene.solver.fail(key, "no " + key + " with scheme = \"wcsph\" (the linear-solver keys belong to scheme = \"isph\")");
  }
  // Fang et al. eq. (51) with the thesis' coefficient.
  double defaultCfl() const override { return kWcsphDefaultCfl; }
  // The sound speed; without a pressure model (a scene without an equation of state) the
  // flow's speed scale.
  double defaultSpeedGuard(const SphSystem<D>& system, double velocity_scale) const override {
    const double sound = system.pressureModel() ? system.pressureModel()->soundSpeed() : 0.0;
    return sound > 0 ? sound : flowSpeedGuard(system, velocity_scale);
  }
};

template <int D>
std::unique_ptr<PressureScheme<D>> makeWcsphScheme() {
  return std::make_unique<WcsphScheme<D>>();
}

template std::unique_ptr<PressureScheme<2>> makeWcsphScheme<2>();
template std::unique_ptr<PressureScheme<3>> makeWcsphScheme<3>();

}  // namespace vesph
