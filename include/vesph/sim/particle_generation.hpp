#pragma once
// Particles from the scene's geometry (docs/architecture.md "Scenes"): the [[blocks]] of fluid
// and walls on a lattice of spacing dx, fluid first (the moving particles), then the walls.
#include <string>
#include <vector>

#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/particles.hpp"
#include "vesph/io/config.hpp"

namespace vesph {

template <int D>
struct LatticeGeometry {
  const std::string& file;  // the scene file, for messages
  double spacing = 0;       // dx, m
  double rest_density = 0;  // rho0: every particle's initial density; its mass rho0 dx^D
  const Domain<D>& domain;
  const Kernel& kernel;     // a wall must be one kernel support thick
};

// Reads [[blocks]] (and [initial] velocity) and adds their particles to `particles` (ids from
// 0). Returns per wall particle its treatment (image walls, pressure floors), or an empty list
// when every wall is plain dummy layers.
template <int D>
std::vector<WallPoint<D>> generateParticles(ConfigTable& root, const LatticeGeometry<D>& geometry,
                                            ParticleSet<D>& particles);

// Wall particles within 1.5 dx of the initial fluid are "wall" (kind 1), deeper layers "dummy"
// (kind 2); inflow buffer particles keep their kind. Needs the neighbour list of the set.
template <int D>
void markWallLayers(ParticleSet<D>& particles, const NeighbourList<D>& list, const Domain<D>& domain, double spacing);

}  // namespace vesph
