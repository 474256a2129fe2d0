#pragma once
// Boundaries as plug-ins (docs/architecture.md "Boundaries" and "Adding a boundary"): walls,
// inflow/outflow and the domain exit are built from the scene by one function each, defined in
// the boundary's own file and listed once in src/boundary/registry.cpp. A boundary adds a
// Boundary (acting on fixed particles inside the right-hand side), step hooks (acting between
// steps), or both, and tells the rest of the scene what it needs to know (BoundaryFacts: the
// pressure scheme's validation, the default scales, the run's checks).
#include <memory>
#include <string>
#include <vector>

#include "vesph/boundary/boundary.hpp"
#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/io/config.hpp"
#include "vesph/physics/step_hook.hpp"

namespace vesph {

// What the built boundaries tell the rest of the scene.
struct BoundaryFacts {
  bool open = false;                  // [inflow] or [outflow]
  bool inflow_buffer = false;         // an inflow buffer of fixed particles
  bool extrapolated_inflow = false;   // inflow.velocity = "extrapolated" (a pressure inlet)
  double prescribed_peak_speed = 0;   // m/s, of a prescribed inflow or moving wall (0: none)
  bool removes_leaving = false;       // checks.leave_domain = "remove"
  // The inflow buffer's flow direction e = inflow_sign e_axis (the ISPH velocity inlet's
  // direction); inflow_axis < 0 without a buffer.
  int inflow_axis = -1;
  double inflow_sign = 1;
};

// The particles of one [[blocks]] table (scene order): [first, first + count) in the particle
// set as built by the blocks (sim/particle_generation), its kind and wall treatment.
struct BlockParticles {
  std::size_t first = 0, count = 0;
  bool wall = false;
  bool image = false;
};

template <int D>
struct BoundaryBuild {
  // What the boundaries are built from: the scene, the particles of its blocks (a boundary may
  // append fixed particles), and per fixed particle of the blocks its wall treatment (empty:
  // dummy layers without a pressure floor everywhere).
  ConfigTable& root;
  ParticleSet<D>& particles;
  const Domain<D>& domain;
  double spacing = 0, rest_density = 0, support = 0;
  std::vector<WallPoint<D>>& wall_points;
  const std::vector<BlockParticles>& blocks;  // per [[blocks]] table, in scene order
  // What they add, in registry order: boundaries for the right-hand side, hooks to run after the
  // pressure scheme's hooks, and the facts.
  std::vector<std::unique_ptr<Boundary<D>>> boundaries;
  std::vector<std::unique_ptr<StepHook<D>>> hooks;
  BoundaryFacts facts;
};

template <int D>
struct BoundaryEntry {
  std::string name;
  std::string summary;
  void (*build)(BoundaryBuild<D>&);
};

// In the order they are built: a boundary may read the facts of those before it.
template <int D>
const std::vector<BoundaryEntry<D>>& boundaryRegistry();

template <int D>
void buildBoundaries(BoundaryBuild<D>& build);

}  // namespace vesph
