#include "vesph/boundary/registry.hpp"

namespace vesph {

// One line per boundary: name, build function (defined in the boundary's own file), summary.
// The order is the build order: the inflow buffer appends fixed particles that the walls then
// cover (as dummy layers), and its hook runs before the domain exit's. The moving walls come
// before the dummy walls: their wall_acceleration field exists when the dummy walls set up.
#define VESPH_BOUNDARIES(X)                                                                         \
  X(inflow_outflow, buildInflowOutflow, "[inflow]: a buffer of fixed particles (kind 3) feeding fluid through an inlet plane, velocity = \"prescribed\" or \"extrapolated\"; [outflow]: fluid particles past a plane are removed")   \
  X(moving_walls, buildMovingWalls, "wall blocks with a prescribed rigid motion ([[blocks]] kind = \"wall\": velocity, angular_velocity, axis_point, ramp_time): positions and velocities set from t before every evaluation") \
  X(dummy_walls, buildDummyWalls, "wall particles ([[blocks]] kind = \"wall\"), no-slip: dummy layers (Adami et al. 2012), or with treatment = \"image\" boundary + image particles (Fang et al. 2006 eqs. 46-48)") \
  X(domain_exit, buildDomainExit, "removal of fluid particles that leave the domain (checks.leave_domain = \"remove\")")

#define VESPH_DECLARE(NAME, FN, SUMMARY) \
  template <int D>                       \
  void FN(BoundaryBuild<D>&);
VESPH_BOUNDARIES(VESPH_DECLARE)

template <int D>
const std::vector<BoundaryEntry<D>>& boundaryRegistry() {
#define VESPH_ENTRY(NAME, FN, SUMMARY) BoundaryEntry<D>{#NAME, SUMMARY, &FN<D>},
  static const std::vector<BoundaryEntry<D>> registry = {VESPH_BOUNDARIES(VESPH_ENTRY)};
  return registry;
}

template <int D>
void buildBoundaries(BoundaryBuild<D>& build) {
  for (const BoundaryEntry<D>& entry : boundaryRegistry<D>()) entry.build(build);
}

template const std::vector<BoundaryEntry<2>>& boundaryRegistry<2>();
template const std::vector<BoundaryEntry<3>>& boundaryRegistry<3>();
template void buildBoundaries<2>(BoundaryBuild<2>&);
template void buildBoundaries<3>(BoundaryBuild<3>&);

}  // namespace vesph
