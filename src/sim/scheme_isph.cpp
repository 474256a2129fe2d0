// The incompressible scheme (docs/architecture.md "Pressure schemes"): the pressure projection
// after every step (src/isph, include/vesph/isph/projection.hpp) under every integrator.
// Here: what the projection cannot do yet, refused at setup with the fix; the step limit's
// default (thesis §3.5) and the speed guard without a sound speed.
#include <algorithm>
#include <cmath>
#include <optional>

#include "vesph/isph/projection.hpp"
#include "vesph/sim/pressure_scheme.hpp"

namespace vesph {

template <int D>
class IsphScheme final : public PressureScheme<D> {
 public:
  std::string_view name() const override { return "isph"; }
  void build(SchemeBuild<D>& scene) const override {
    refuseWalls(scene);
    refuseOpenBoundaries(scene);
    // The velocity inlet's direction, from the prescribed inflow buffer (it does not change).
    std::optional<Vec<D>> inflow_direction;
    if (scene.boundaries.inflow_axis >= 0) {
      inflow_direction = Vec<D>::Zero();
      (*inflow_direction)[scene.boundaries.inflow_axis] = scene.boundaries.inflow_sign;
    }
    scene.hooks.push_back(makeProjection<D>(scene.solver, inflow_direction));
  }
  // Thesis §3.5: without acoustic waves the CFL limit on the flow speed allows a larger
  // coefficient.
  double defaultCfl() const override { return kIsphDefaultCfl; }
  // No sound speed (an equation of state is refused with this scheme): the flow's speed scale.
  double defaultSpeedGuard(const SphSystem<D>& system, double velocity_scale) const override {
    return flowSpeedGuard(system, velocity_scale);
  }

 private:
  static void refuseWalls(const SchemeBuild<D>& scene) {
    for (const WallPoint<D>& w : scene.wall_points) {
      if (w.image)
        throw InputError(scene.file + ": blocks: treatment = \"image\" walls are not implemented with solver.scheme = "
                         "\"isph\" (the projection extrapolates the wall pressure as for dummy layers); use treatment = \"dummy\"");
      if (std::isfinite(w.pressure_floor))
        throw InputError(scene.file + ": blocks: pressure_floor is not implemented with solver.scheme = \"isph\" "
                         "(the projection solves the wall pressures with the fluid's); remove it or use scheme = \"wcsph\"");
    }
  }
  // A prescribed inflow is a velocity inlet: for the pressure Poisson equation a Neumann
  // boundary like a wall, with the buffer's velocity in the divergence. The extrapolated
  // (pressure) inlet would need a Dirichlet pressure on the buffer, which the projection does
  // not have. Open ends need p = 0 on the particles with a cut support (free-surface
  // detection): without it the open channel diverged within 34 steps.
  static void refuseOpenBoundaries(const SchemeBuild<D>& scene) {
    const BoundaryFacts& open = scene.boundaries;
    if (open.open && open.extrapolated_inflow)
      throw InputError(scene.file + ": inflow.velocity = \"extrapolated\" is not implemented with solver.scheme = \"isph\" "
                       "(the projection takes the buffer as a Neumann boundary, right for a prescribed velocity only); "
                       "use velocity = \"prescribed\" or scheme = \"wcsph\"");
    if (open.open && std::none_of(scene.effects.begin(), scene.effects.end(),
                                  [](const auto& e) { return e->name() == "free_surface"; }))
      throw InputError(scene.file + ": inflow/outflow with solver.scheme = \"isph\" need [effects.free_surface] "
                       "(threshold = 0.97): the open ends are free surfaces with p = 0");
    if ((!open.open || !open.inflow_buffer) && scene.solver.has("inlet_condition"))
      scene.solver.fail("inlet_condition", "only with a prescribed [inflow] (the condition is the buffer's)");
  }
};

template <int D>
std::unique_ptr<PressureScheme<D>> makeIsphScheme() {
  return std::make_unique<IsphScheme<D>>();
}

template std::unique_ptr<PressureScheme<2>> makeIsphScheme<2>();
template std::unique_ptr<PressureScheme<3>> makeIsphScheme<3>();

}  // namespace vesph
