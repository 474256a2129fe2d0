#pragma once
// Particles from the scene's geometry (docs/architecture.md "Scenes"): the [[blocks]] of fluid
// and walls on a lattice of spacing dx, fluid first (the moving particles), then the walls.
#include <optional>
#include <string>
#include <vector>

#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/boundary/registry.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/particles.hpp"
#include "vesph/io/config.hpp"
#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
struct LatticeGeometry {
  const std::string& file;  // the scene file, for messages
  double spacing = 0;       // dx, m
  double rest_density = 0;  // rho0: every particle's initial density; its mass rho0 dx^D
  const Domain<D>& domain;
  const Kernel& kernel;     // a wall must be one kernel support thick
};

// A fluid block that starts in hydrostatic equilibrium ([[blocks]] hydrostatic = true): its
// particles [first, last) and its extent, for the density applied once the equation of state
// and the body acceleration are known (applyHydrostaticDensity).
template <int D>
struct HydrostaticBlock {
  std::size_t first = 0, last = 0;
  Vec<D> lo = Vec<D>::Zero(), hi = Vec<D>::Zero();
  std::optional<double> surface_height;  // m, along -g; absent: the block's top
  std::string path;                      // for messages
};

// What `vesph check` reports per [[blocks]] table (scene order): its particle count and summed
// particle volume sum m/rho0 against the shape's analytic volume less its subtractions
// (docs/user-guide.md "[[blocks]]"; NaN where a subtraction cuts across the shape's surface and
// no analytic value exists).
struct BlockSummary {
  std::string path;   // "blocks[k]"
  std::string kind;   // "fluid" / "wall"
  std::string shape;  // "box", "disk", "sphere", "cylinder", "tube"
  std::size_t count = 0;
  double volume = 0;            // m^D: sum over the block's particles of m / rho0
  double reference_volume = 0;  // m^D: the analytic volume (NaN: unknown)
};

// Reads [[blocks]] (and [initial] velocity) and adds their particles to `particles` (ids from
// 0). Returns per wall particle its treatment (image walls, pressure floors), or an empty list
// when every wall is plain dummy layers. The fluid blocks marked hydrostatic go to
// `hydrostatic` when given (otherwise the key is refused). `spans`, when given, receives per
// [[blocks]] table (scene order) its particles (the moving walls' blocks); `summaries`, when
// given, per block its count and volumes. Throws InputError when particles of two blocks lie
// closer than half a spacing (the blocks overlap).
template <int D>
std::vector<WallPoint<D>> generateParticles(ConfigTable& root, const LatticeGeometry<D>& geometry,
                                            ParticleSet<D>& particles,
                                            std::vector<HydrostaticBlock<D>>* hydrostatic = nullptr,
                                            std::vector<BlockParticles>* spans = nullptr,
                                            std::vector<BlockSummary>* summaries = nullptr);

// The hydrostatic initial density (docs/theory.md "Hydrostatic initial density"): each particle
// of the blocks gets the density whose pressure is the hydrostatic one under the body
// acceleration g,  p = p(rho0) + rho0 |g| (H - z),  z = x . (-g/|g|) its height and H the
// block's free-surface height, by the equation of state's inverse (linear or Tait). The mass
// stays rho0 dx^D. Throws InputError (naming the block) without an equation of state or g.
template <int D>
void applyHydrostaticDensity(const std::vector<HydrostaticBlock<D>>& blocks, const PressureModel* model,
                             const Vec<D>& body_acceleration, double rest_density, const std::string& file,
                             ParticleSet<D>& particles);

// Wall particles within 1.5 dx of the initial fluid are "wall" (kind 1), deeper layers "dummy"
// (kind 2); inflow buffer particles keep their kind. Needs the neighbour list of the set.
template <int D>
void markWallLayers(ParticleSet<D>& particles, const NeighbourList<D>& list, const Domain<D>& domain, double spacing);

}  // namespace vesph
