#include "vesph/sim/particle_generation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <tuple>

#include <unistd.h>

namespace vesph {
namespace {

// A block is a box (min, max: particles at the cell centres of a lattice of spacing dx) or,
// for fluid, a disk (2D) / sphere (3D) of the given centre and diameter: the nodes
// centre + k dx (k integer) inside the circle, the Cartesian lattice cut by the circle of
// Fang et al. (2006) §4 (D = 2 cm, dx = 0.02 cm: 7845 particles).
template <int D>
struct Block {
  ParticleKind kind;
  Vec<D> lo, hi;  // the bounding box for a disk
  std::string path;
  bool disk = false;
  Vec<D> centre = Vec<D>::Zero();
  double radius = 0;
  Vec<D> velocity = Vec<D>::Zero();
  double jitter = 0;       // fluid: random displacement of each particle, fraction of dx
  std::uint64_t seed = 1;  // of the jitter's random sequence (reproducible)
  bool image = false;      // wall: Fang et al. (2006) §3.3 boundary + image particles
  int normal_axis = 0;     // image wall: its surface faces +-e_axis (into the fluid)
  double normal_sign = 1;
  bool centroid = false;   // image wall: extrapolate from the centroid of P's weights
  double pressure_floor = -std::numeric_limits<double>::infinity();  // dummy wall, Pa
  bool hydrostatic = false;              // fluid: hydrostatic initial density
  std::optional<double> surface_height{};  // its free surface, m along -g (absent: the block's top)
};

template <int D>
class BlockReader {
 public:
  BlockReader(const LatticeGeometry<D>& g, const Vec<D>& initial_velocity) : g_(g), v0_(initial_velocity) {}

  Block<D> read(ConfigTable& b) const {
    const std::string kind = b.choice("kind", std::nullopt, {"fluid", "wall"});
    const std::string shape = b.choice("shape", "box", {"box", roundName()});
    Block<D> block{kind == "fluid" ? ParticleKind::fluid : ParticleKind::wall, Vec<D>::Zero(), Vec<D>::Zero(), b.path()};
    if (kind == "fluid") {
      block.velocity = b.vector<D>("velocity", v0_, "m/s");
      // A lattice aligned with the flow can persist as particle columns (the drop's opening,
      // docs/validation.md §10); a small random displacement breaks it. Uniform in
      // [-jitter/2, jitter/2] dx per axis; the mass stays rho0 dx^D.
      block.jitter = b.numberIn("jitter", 0.0, 0.0, 0.5, "of the particle spacing");
      block.seed = static_cast<std::uint64_t>(b.integer("seed", 1, 0, 1LL << 62));
      // Read only when present: the resolved scenes of existing cases stay as they were.
      if (b.has("hydrostatic")) block.hydrostatic = b.boolean("hydrostatic", false);
      if (b.has("surface_height")) {
        if (!block.hydrostatic) b.fail("surface_height", "no surface_height without hydrostatic = true");
        block.surface_height = b.number("surface_height", std::nullopt, Bound::any, "m");
      }
    } else {
      for (const char* key : {"hydrostatic", "surface_height"})
        if (b.has(key)) b.fail(key, "no " + std::string(key) + " on a wall block (a fluid block's initial density)");
    }
    if (shape != "box") {
      if (kind != "fluid") b.fail("shape", "\"box\" for a wall block (walls are boxes of layers)");
      readRound(b, block);
      return block;
    }
    block.lo = b.vector<D>("min", std::nullopt, "m");
    block.hi = b.vector<D>("max", std::nullopt, "m");
    if (kind == "wall") readWallTreatment(b, block);
    else if (b.has("pressure_floor")) b.fail("pressure_floor", "no pressure_floor on a fluid block (it bounds a wall's pressure)");
    checkBoxExtent(b, block);
    if (block.kind == ParticleKind::wall) checkWallThickness(b, block);
    return block;
  }

 private:
  static std::string roundName() { return D == 2 ? "disk" : "sphere"; }

  void readRound(ConfigTable& b, Block<D>& block) const {
    block.disk = true;
    block.centre = b.vector<D>("centre", std::nullopt, "m");
    block.radius = 0.5 * b.number("diameter", std::nullopt, Bound::positive, "m");
    if (block.radius < g_.spacing) b.fail("diameter", "at least two particle spacings");
    block.lo = block.centre.array() - block.radius;
    block.hi = block.centre.array() + block.radius;
    for (int a = 0; a < D; ++a)
      if (block.lo[a] < g_.domain.lo[a] || block.hi[a] > g_.domain.hi[a])
        b.fail("centre", "a " + roundName() + " inside the domain [domain.min, domain.max]");
  }

  // Per wall: vesph's dummy layers (Adami et al. 2012) or Fang's boundary particles on the
  // wall surface plus image particles behind it (include/vesph/boundary/dummy_walls.hpp).
  static void readWallTreatment(ConfigTable& b, Block<D>& block) {
    block.image = b.choice("treatment", "dummy", {"dummy", "image"}) == "image";
    if (block.image) {
      std::tie(block.normal_axis, block.normal_sign) = b.coordinateAxis<D>(
          "normal", "a coordinate unit vector pointing from the wall into the fluid, e.g. [0.0, 1.0] for a floor");
      block.centroid = b.choice("extrapolation", "fang", {"fang", "centroid"}) == "centroid";
    }
    if (b.has("pressure_floor")) {
      // A wall that pushes but does not pull (at 0): theory.md §6, the die's lip in
      // docs/studies.md §5.
      if (block.image) b.fail("pressure_floor", "no pressure_floor with treatment = \"image\" (dummy layers only)");
      block.pressure_floor = b.number("pressure_floor", std::nullopt, Bound::any, "Pa");
    }
  }

  void checkBoxExtent(ConfigTable& b, const Block<D>& block) const {
    const double dx = g_.spacing;
    for (int a = 0; a < D; ++a) {
      const double L = block.hi[a] - block.lo[a];
      if (!(L > 0)) b.fail("max", "a corner above min along every axis");
      const double cells = L / dx;
      if (std::abs(cells - std::round(cells)) > 1e-6 * std::max(1.0, cells)) {
        std::ostringstream os;
        os << "an extent that is a whole number of particle spacings (" << dx << " m) along axis " << a
           << "; the extent " << L << " m is " << cells << " spacings";
        b.fail("max", os.str());
      }
      const double tol = 1e-9 * g_.domain.length(a);
      if (block.lo[a] < g_.domain.lo[a] - tol || block.hi[a] > g_.domain.hi[a] + tol)
        b.fail("max", "a block inside the domain [domain.min, domain.max]");
    }
  }

  void checkWallThickness(ConfigTable& b, const Block<D>& block) const {
    double thinnest = 1e300;
    for (int a = 0; a < D; ++a)
      if (!(g_.domain.periodic[a])) thinnest = std::min(thinnest, block.hi[a] - block.lo[a]);
    const double support = g_.kernel.supportRadius();
    if (thinnest < support * (1 - 1e-9)) {
      std::ostringstream os;
      os << "a wall at least one kernel support thick (" << support << " m = " << std::ceil(support / g_.spacing - 1e-9)
         << " layers, thesis 4.2) across its thinnest non-periodic extent, which is " << thinnest << " m";
      b.fail("max", os.str());
    }
  }

  const LatticeGeometry<D>& g_;
  Vec<D> v0_;
};

// Blocks must not overlap (a particle would sit on another).
template <int D>
void checkOverlaps(const std::vector<Block<D>>& blocks, const LatticeGeometry<D>& g) {
  for (std::size_t i = 0; i < blocks.size(); ++i)
    for (std::size_t j = i + 1; j < blocks.size(); ++j) {
      bool overlap = true;
      for (int a = 0; a < D; ++a)
        overlap = overlap && std::min(blocks[i].hi[a], blocks[j].hi[a]) - std::max(blocks[i].lo[a], blocks[j].lo[a]) >
                                 1e-9 * g.spacing;
      if (overlap)
        throw InputError(g.file + ": " + blocks[j].path + ": overlaps " + blocks[i].path +
                         (blocks[i].disk || blocks[j].disk ? " (a disk or sphere counts with its bounding box)" : ""));
    }
}

// The particle count estimated from the blocks' volumes (bounding boxes for disks and spheres;
// image walls twice, boundary and image particles) before any is placed: a tiny
// particles.spacing filled the memory until std::bad_alloc. Refused when the particles would
// not fit in the machine's memory at about kBytesPerParticle each (state, particle set,
// neighbour list, right-hand side, integrator stages).
constexpr double kBytesPerParticle = 1024;

template <int D>
void checkParticleCount(const std::vector<Block<D>>& blocks, const LatticeGeometry<D>& g) {
  double count = 0;
  for (const Block<D>& b : blocks) {
    double n = b.image ? 2.0 : 1.0;
    for (int a = 0; a < D; ++a) n *= std::floor((b.hi[a] - b.lo[a]) / g.spacing + 0.5) + 1.0;
    count += n;
  }
  const double memory = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGE_SIZE));
  if (memory > 0 && count * kBytesPerParticle > memory) {
    std::ostringstream os;
    os.precision(3);
    os << g.file << ": particles.spacing: the blocks hold about " << count << " particles at a spacing of " << g.spacing
       << " m, about " << count * kBytesPerParticle / (1 << 30) << " GiB at " << static_cast<int>(kBytesPerParticle)
       << " bytes each, more than the " << memory / (1 << 30) << " GiB of memory of this machine";
    throw InputError(os.str());
  }
}

// Places the particles of the blocks, fluid blocks first, with consecutive ids.
template <int D>
class LatticePlacer {
 public:
  LatticePlacer(const LatticeGeometry<D>& g, ParticleSet<D>& p, std::vector<WallPoint<D>>& wall_points)
      : g_(g), p_(p), wall_points_(wall_points), mass_(g.rest_density * std::pow(g.spacing, D)) {}

  void place(const std::vector<Block<D>>& blocks, std::vector<HydrostaticBlock<D>>* hydrostatic,
             std::vector<BlockParticles>* spans) {
    if (spans) spans->assign(blocks.size(), BlockParticles{});
    for (ParticleKind pass : {ParticleKind::fluid, ParticleKind::wall})
      for (std::size_t k = 0; k < blocks.size(); ++k) {
        const Block<D>& b = blocks[k];
        if (b.kind != pass) continue;
        const std::size_t first = p_.size();
        if (b.disk) placeRound(b);
        else placeBox(b, pass);
        if (b.hydrostatic && hydrostatic) hydrostatic->push_back({first, p_.size(), b.lo, b.hi, b.surface_height, b.path});
        if (spans) (*spans)[k] = BlockParticles{first, p_.size() - first, pass == ParticleKind::wall, b.image};
      }
  }

 private:
  void add(const Vec<D>& x, const Block<D>& b, ParticleKind kind) {
    p_.add(Vec<D>(x + jitter(b)), b.velocity, g_.rest_density, mass_, kind, next_id_++);
  }

  Vec<D> jitter(const Block<D>& b) {
    Vec<D> d = Vec<D>::Zero();
    if (b.jitter <= 0) return d;
    if (rng_block_ != &b) {  // each block its own sequence, from its seed
      rng_.seed(b.seed);
      rng_block_ = &b;
    }
    for (int a = 0; a < D; ++a) d[a] = b.jitter * g_.spacing * unit_(rng_);
    return d;
  }

  void placeRound(const Block<D>& b) {
    const double dx = g_.spacing;
    const long reach = static_cast<long>(std::floor(b.radius / dx + 1e-9));
    const double r2max = b.radius * b.radius * (1 + 1e-12);
    std::array<long, D> k;
    k.fill(-reach);
    while (true) {
      Vec<D> off;
      for (int a = 0; a < D; ++a) off[a] = static_cast<double>(k[a]) * dx;
      if (off.squaredNorm() <= r2max) add(Vec<D>(b.centre + off), b, ParticleKind::fluid);
      int a = 0;
      while (a < D && ++k[a] > reach) k[a++] = -reach;
      if (a == D) break;
    }
  }

  void placeBox(const Block<D>& b, ParticleKind pass) {
    const double dx = g_.spacing;
    std::array<long, D> n;
    long total = 1;
    for (int a = 0; a < D; ++a) {
      n[a] = std::lround((b.hi[a] - b.lo[a]) / dx);
      // An image wall: one row on the surface (the boundary particles) and one row per
      // spacing of the block's depth behind it (the image particles), Fang et al. Fig. 1.
      if (b.image && a == b.normal_axis) ++n[a];
      total *= n[a];
    }
    const std::size_t first = p_.size();
    for (long k = 0; k < total; ++k) {
      long rem = k;
      Vec<D> x;
      std::array<long, D> idx;
      for (int a = 0; a < D; ++a) {
        idx[a] = rem % n[a];
        x[a] = b.lo[a] + (static_cast<double>(idx[a]) + 0.5) * dx;
        rem /= n[a];
      }
      if (b.image) {
        const int a = b.normal_axis;
        const double surface = b.normal_sign > 0 ? b.hi[a] : b.lo[a];
        x[a] = surface - b.normal_sign * static_cast<double>(idx[a]) * dx;
        wall_points_.push_back(imagePoint(b, idx, n, first));
      } else if (pass == ParticleKind::wall) {
        WallPoint<D> w;
        w.pressure_floor = b.pressure_floor;
        wall_points_.push_back(w);
      }
      add(x, b, pass);
    }
  }

  // The image wall point at lattice index idx of a box of n cells whose first particle is first.
  WallPoint<D> imagePoint(const Block<D>& b, const std::array<long, D>& idx, const std::array<long, D>& n,
                          std::size_t first) const {
    const int a = b.normal_axis;
    WallPoint<D> w;
    w.image = true;
    w.normal = Vec<D>::Zero();
    w.normal[a] = b.normal_sign;
    w.depth = static_cast<double>(idx[a]) * g_.spacing;
    w.centroid = b.centroid;
    // The boundary particle of the same column: row 0 (idx[a] = 0), same other indices.
    long kb = 0, stride = 1;
    for (int c = 0; c < D; ++c) {
      kb += stride * (c == a ? 0 : idx[c]);
      stride *= n[c];
    }
    w.boundary = static_cast<Index>(first + static_cast<std::size_t>(kb));
    return w;
  }

  const LatticeGeometry<D>& g_;
  ParticleSet<D>& p_;
  std::vector<WallPoint<D>>& wall_points_;
  double mass_;
  std::uint64_t next_id_ = 0;
  std::mt19937_64 rng_;
  const Block<D>* rng_block_ = nullptr;
  std::uniform_real_distribution<double> unit_{-0.5, 0.5};
};

}  // namespace

template <int D>
std::vector<WallPoint<D>> generateParticles(ConfigTable& root, const LatticeGeometry<D>& geometry,
                                            ParticleSet<D>& particles, std::vector<HydrostaticBlock<D>>* hydrostatic,
                                            std::vector<BlockParticles>* spans) {
  const Vec<D> v0 = root.table("initial").vector<D>("velocity", Vec<D>::Zero(), "m/s");
  auto tables = root.tableArray("blocks");
  if (tables.empty()) root.fail("blocks", "at least one [[blocks]] table with kind, min and max");
  const BlockReader<D> reader(geometry, v0);
  std::vector<Block<D>> blocks;
  for (ConfigTable& b : tables) blocks.push_back(reader.read(b));
  checkOverlaps(blocks, geometry);
  checkParticleCount(blocks, geometry);

  std::vector<WallPoint<D>> wall_points;
  if (!hydrostatic)
    for (const Block<D>& b : blocks)
      if (b.hydrostatic) throw InputError(geometry.file + ": " + b.path + ".hydrostatic: not available here");
  LatticePlacer<D>(geometry, particles, wall_points).place(blocks, hydrostatic, spans);
  if (particles.n_moving == 0) root.fail("blocks", "at least one block of kind \"fluid\"");
  // Scenes without image walls or pressure floors keep no per-wall-particle record
  // (DummyWalls treats an empty one as all dummy layers without a floor).
  if (std::none_of(wall_points.begin(), wall_points.end(),
                   [](const WallPoint<D>& w) { return w.image || std::isfinite(w.pressure_floor); }))
    std::vector<WallPoint<D>>().swap(wall_points);
  return wall_points;
}

template <int D>
void markWallLayers(ParticleSet<D>& p, const NeighbourList<D>& list, const Domain<D>& domain, double spacing) {
  // Both kinds are treated alike; the distinction helps when looking at output.
  const double reach2 = 2.25 * spacing * spacing;
  for (std::size_t w = p.n_moving; w < p.size(); ++w) {
    if (p.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow)) continue;
    bool touches = false;
    for (std::size_t k = list.start[w]; k < list.split[w] && !touches; ++k) {
      const Index j = list.nbr[k];
      double r2 = 0;
      for (int a = 0; a < D; ++a) {
        const double d = domain.image(a, p.position[D * w + a] - p.position[D * j + a]);
        r2 += d * d;
      }
      touches = r2 <= reach2;
    }
    p.kind[w] = static_cast<std::uint8_t>(touches ? ParticleKind::wall : ParticleKind::dummy);
  }
}

template <int D>
void applyHydrostaticDensity(const std::vector<HydrostaticBlock<D>>& blocks, const PressureModel* model,
                             const Vec<D>& body_acceleration, double rest_density, const std::string& file,
                             ParticleSet<D>& particles) {
  for (const HydrostaticBlock<D>& b : blocks) {
    if (!model)
      throw InputError(file + ": " + b.path + ".hydrostatic: needs an equation of state to give the density of the "
                       "hydrostatic pressure (add [effects.equation_of_state]; ISPH solves its pressure itself)");
    const double g = body_acceleration.norm();
    if (!(g > 0))
      throw InputError(file + ": " + b.path + ".hydrostatic: needs a body acceleration (add [effects.body_force])");
    const Vec<D> up = -body_acceleration / g;
    // The block's top along -g: the highest corner of its box (a disk's or sphere's bounding box).
    double top = -1e300;
    for (int corner = 0; corner < (1 << D); ++corner) {
      Vec<D> x;
      for (int a = 0; a < D; ++a) x[a] = (corner >> a) & 1 ? b.hi[a] : b.lo[a];
      top = std::max(top, x.dot(up));
    }
    const double surface = b.surface_height.value_or(top);
    const double p_surface = model->pressure(rest_density);  // the free surface keeps rho0
    for (std::size_t i = b.first; i < b.last; ++i) {
      const double depth = surface - Vec<D>(particles.x(i)).dot(up);
      particles.density[i] = model->densityFor(p_surface + rest_density * g * depth);
    }
  }
}

template std::vector<WallPoint<2>> generateParticles<2>(ConfigTable&, const LatticeGeometry<2>&, ParticleSet<2>&,
                                                        std::vector<HydrostaticBlock<2>>*, std::vector<BlockParticles>*);
template std::vector<WallPoint<3>> generateParticles<3>(ConfigTable&, const LatticeGeometry<3>&, ParticleSet<3>&,
                                                        std::vector<HydrostaticBlock<3>>*, std::vector<BlockParticles>*);
template void applyHydrostaticDensity<2>(const std::vector<HydrostaticBlock<2>>&, const PressureModel*, const Vec<2>&,
                                         double, const std::string&, ParticleSet<2>&);
template void applyHydrostaticDensity<3>(const std::vector<HydrostaticBlock<3>>&, const PressureModel*, const Vec<3>&,
                                         double, const std::string&, ParticleSet<3>&);
template void markWallLayers<2>(ParticleSet<2>&, const NeighbourList<2>&, const Domain<2>&, double);
template void markWallLayers<3>(ParticleSet<3>&, const NeighbourList<3>&, const Domain<3>&, double);

}  // namespace vesph
