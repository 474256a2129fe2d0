#include "vesph/sim/particle_generation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <tuple>

#include <unistd.h>

#include <Eigen/Geometry>  // cross products (frame = "polar" checks)

#include "vesph/boundary/moving_walls.hpp"  // kWallMotionKeys

namespace vesph {
namespace {

// The shapes of [[blocks]] and of their `subtract` lists (docs/user-guide.md "[[blocks]]"):
//   box       the axis-aligned box [lo, hi];
//   ball      a disk (2D) / sphere (3D) of the given centre and radius;
//   cylinder  2D: its cross-section, a disk; 3D: radius, unit axis, length, centred at `centre`;
//   tube      the annulus (2D) / hollow cylinder (3D) between inner_radius and radius.
enum class ShapeKind { box, ball, cylinder, tube };

template <int D>
struct Solid {
  ShapeKind kind = ShapeKind::box;
  Vec<D> lo = Vec<D>::Zero(), hi = Vec<D>::Zero();  // the box; the bounding box of the others
  Vec<D> centre = Vec<D>::Zero();
  double radius = 0, inner_radius = 0;  // m
  Vec<D> axis = Vec<D>::Zero();         // 3D cylinder / tube: unit vector
  double length = 0;                    // 3D cylinder / tube, m

  bool curved() const { return kind != ShapeKind::box; }

  // x inside the closed shape grown by `slack` (m).
  bool contains(const Vec<D>& x, double slack) const {
    switch (kind) {
      case ShapeKind::box:
        for (int a = 0; a < D; ++a)
          if (x[a] < lo[a] - slack || x[a] > hi[a] + slack) return false;
        return true;
      case ShapeKind::ball: return (x - centre).norm() <= radius + slack;
      case ShapeKind::cylinder:
      case ShapeKind::tube: {
        Vec<D> d = x - centre;
        if constexpr (D == 3) {
          const double s = d.dot(axis);
          if (std::abs(s) > 0.5 * length + slack) return false;
          d -= s * axis;
        }
        const double r = d.norm();
        return r <= radius + slack && (kind == ShapeKind::cylinder || r >= inner_radius - slack);
      }
    }
    return false;
  }

  // The analytic volume (area in 2D), m^D.
  double volume() const {
    const double pi = std::numbers::pi;
    switch (kind) {
      case ShapeKind::box: return (hi - lo).prod();
      case ShapeKind::ball: return D == 2 ? pi * radius * radius : 4.0 / 3.0 * pi * radius * radius * radius;
      case ShapeKind::cylinder:
      case ShapeKind::tube: {
        const double area = pi * (radius * radius - inner_radius * inner_radius);
        return D == 2 ? area : area * length;
      }
    }
    return 0;
  }

  // The bounding box of a curved shape from its parameters.
  void bound() {
    if (kind == ShapeKind::box) return;
    for (int a = 0; a < D; ++a) {
      double reach = radius;
      if constexpr (D == 3)
        if (kind != ShapeKind::ball) {
          // A disk of radius R normal to the axis e reaches R sqrt(1 - e_a^2) along axis a.
          const double e = axis[a];
          reach = 0.5 * length * std::abs(e) + radius * std::sqrt(std::max(0.0, 1.0 - e * e));
        }
      lo[a] = centre[a] - reach;
      hi[a] = centre[a] + reach;
    }
  }
};

// A block: a shape filled with particles, less its subtracted shapes.
//  * box: particles at the cell centres of a lattice of spacing dx anchored at min;
//  * fluid disk / sphere: the nodes centre + k dx (k integer) inside the circle, the Cartesian
//    lattice cut by the circle of Fang et al. (2006) §4 (D = 2 cm, dx = 0.02 cm: 7845
//    particles);
//  * cylinder, tube, and wall disks (2D): concentric rings, stacked along the axis in 3D
//    (placeRings); wall spheres: concentric shells (placeShells). Each particle's mass is rho0
//    times its ring's (shell's) cell volume, so the particles' volume is the shape's
//    (docs/theory.md §6.3).
template <int D>
struct Block {
  ParticleKind kind;
  Solid<D> solid;
  std::vector<Solid<D>> subtract;
  std::string path;
  std::string shape_name;  // as written in the scene
  Vec<D> velocity = Vec<D>::Zero();
  double jitter = 0;       // fluid: random displacement of each particle, fraction of dx
  std::uint64_t seed = 1;  // of the jitter's random sequence (reproducible)
  bool image = false;      // wall: Fang et al. (2006) §3.3 boundary + image particles
  int normal_axis = 0;     // image wall: its surface faces +-e_axis (into the fluid)
  double normal_sign = 1;
  bool centroid = false;   // image wall: extrapolate from the centroid of P's weights
  double pressure_floor = -std::numeric_limits<double>::infinity();  // dummy wall, Pa
  bool polar = false;      // dummy wall of a round shape: averaged in its polar frame
  bool linear_stress = false;  // dummy wall: stresses continued linearly from the fluid
  bool free_slip = false;  // dummy wall at rest: slip = "free" (no shear stress)
  int wet_axis = -1;       // dummy box with wetted_face: the axis of the face's normal (-1: none)
  bool hydrostatic = false;              // fluid: hydrostatic initial density
  std::optional<double> surface_height{};  // its free surface, m along -g (absent: the block's top)

  // Placed as concentric rings (shells) with per-particle masses, or on the Cartesian lattice.
  bool rings() const {
    return solid.kind == ShapeKind::cylinder || solid.kind == ShapeKind::tube ||
           (solid.kind == ShapeKind::ball && kind == ParticleKind::wall);
  }
  bool removed(const Vec<D>& x, double slack) const {
    for (const Solid<D>& s : subtract)
      if (s.contains(x, slack)) return true;
    return false;
  }
};

template <int D>
class BlockReader {
 public:
  BlockReader(const LatticeGeometry<D>& g, const Vec<D>& initial_velocity) : g_(g), v0_(initial_velocity) {}

  Block<D> read(ConfigTable& b) const {
    const std::string kind = b.choice("kind", std::nullopt, {"fluid", "wall"});
    const std::string shape = b.choice("shape", "box", shapeNames());
    Block<D> block{kind == "fluid" ? ParticleKind::fluid : ParticleKind::wall, Solid<D>{}, {}, b.path(), shape};
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
    block.solid = readSolid(b, shape, true);
    if (kind == "wall") readWallTreatment(b, block, shape);
    else
      for (const char* key : {"frame", "stress_extrapolation", "slip", "wetted_face"})
        if (b.has(key)) b.fail(key, std::string("no ") + key + " on a fluid block (it sets how a wall takes the fluid's values)");
    else if (b.has("pressure_floor")) b.fail("pressure_floor", "no pressure_floor on a fluid block (it bounds a wall's pressure)");
    if (block.image && shape != "box")
      b.fail("treatment", "\"dummy\" for a " + shape + " (image walls are boxes facing a coordinate axis)");
    if (b.has("subtract")) {
      if (block.image) b.fail("subtract", "no subtract with treatment = \"image\" (its boundary and image rows pair up)");
      for (ConfigTable& t : b.tableArray("subtract"))
        block.subtract.push_back(readSolid(t, t.choice("shape", std::nullopt, shapeNames()), false));
    }
    if (shape == "box") checkBoxExtent(b, block.solid);
    else checkInsideDomain(b, block.solid, shape);
    if (block.kind == ParticleKind::wall) checkWallThickness(b, block.solid, shape);
    return block;
  }

 private:
  static std::string roundName() { return D == 2 ? "disk" : "sphere"; }
  static std::vector<std::string> shapeNames() { return {"box", roundName(), "cylinder", "tube"}; }

  // The keys of one shape (a block's own, or one of its `subtract` list): box min/max,
  // disk/sphere centre/diameter, cylinder centre/diameter(/axis/length), tube
  // centre/inner_diameter/outer_diameter(/axis/length). A block's own shape must span at least
  // two spacings; a subtracted one any positive size.
  Solid<D> readSolid(ConfigTable& b, const std::string& shape, bool own) const {
    Solid<D> s;
    if (shape == "box") {
      s.lo = b.vector<D>("min", std::nullopt, "m");
      s.hi = b.vector<D>("max", std::nullopt, "m");
      if (!own)
        for (int a = 0; a < D; ++a)
          if (!(s.hi[a] > s.lo[a])) b.fail("max", "a corner above min along every axis (m)");
      return s;
    }
    s.centre = b.vector<D>("centre", std::nullopt, "m");
    for (int a = 0; a < D; ++a)
      if (!std::isfinite(s.centre[a])) b.fail("centre", "a finite point (m)");
    const double least = own ? 2 * g_.spacing : 0.0;
    if (shape == "tube") {
      s.kind = ShapeKind::tube;
      s.inner_radius = 0.5 * b.number("inner_diameter", std::nullopt, Bound::positive, "m");
      s.radius = 0.5 * b.number("outer_diameter", std::nullopt, Bound::positive, "m");
      if (!(s.radius - s.inner_radius >= 0.5 * least) || s.radius <= s.inner_radius)
        b.fail("outer_diameter", own ? "at least inner_diameter + two particle spacings (m)"
                                     : "more than inner_diameter (m)");
    } else {
      s.kind = shape == "cylinder" ? ShapeKind::cylinder : ShapeKind::ball;
      s.radius = 0.5 * b.number("diameter", std::nullopt, Bound::positive, "m");
      if (s.radius < 0.5 * least) b.fail("diameter", "at least two particle spacings (m)");
    }
    if (s.kind != ShapeKind::ball) {
      if constexpr (D == 2) {
        for (const char* key : {"axis", "length"})
          if (b.has(key))
            b.fail(key, std::string("no ") + key + " in 2D (a 2D " + shape + " is its cross-section in the plane)");
      } else {
        const Vec<D> axis = b.vector<D>("axis", std::nullopt, "a direction, normalised");
        const double n = axis.norm();
        if (!(n > 0) || !std::isfinite(n)) b.fail("axis", "a non-zero finite direction vector");
        s.axis = axis / n;
        s.length = b.number("length", std::nullopt, Bound::positive, "m");
        if (own && s.length < 2 * g_.spacing) b.fail("length", "at least two particle spacings (m)");
      }
    }
    s.bound();
    return s;
  }

  // Per wall: vesph's dummy layers (Adami et al. 2012) or Fang's boundary particles on the
  // wall surface plus image particles behind it (include/vesph/boundary/dummy_walls.hpp).
  static void readWallTreatment(ConfigTable& b, Block<D>& block, const std::string& shape) {
    block.image = b.choice("treatment", "dummy", {"dummy", "image"}) == "image";
    if (b.has("frame")) readWallFrame(b, block, shape);
    if (b.has("stress_extrapolation")) {
      // The stresses on the wall particles: Fang eq. (46)'s average, or its linear continuation
      // (include/vesph/boundary/dummy_walls.hpp, docs/theory.md §6.3).
      block.linear_stress = b.choice("stress_extrapolation", "shepard", {"shepard", "linear"}) == "linear";
      if (block.linear_stress && block.image)
        b.fail("stress_extrapolation", "\"shepard\" with treatment = \"image\" (Fang's eq. 48 extrapolates those)");
    }
    if (block.image) {
      std::tie(block.normal_axis, block.normal_sign) = b.coordinateAxis<D>(
          "normal", "a coordinate unit vector pointing from the wall into the fluid, e.g. [0.0, 1.0] for a floor");
      block.centroid = b.choice("extrapolation", "fang", {"fang", "centroid"}) == "centroid";
    }
    if (b.has("slip")) {
      // slip = "free": the ghost velocity reflects the fluid's in the wall's plane, a wall
      // without shear stress (include/vesph/boundary/dummy_walls.hpp, docs/theory.md §6.4).
      block.free_slip = b.choice("slip", "no", {"no", "free"}) == "free";
      if (block.free_slip && block.image)
        b.fail("slip", "\"no\" with treatment = \"image\" (Fang's eq. 47 extrapolates through the wall's own velocity; "
                       "free slip is for dummy layers)");
      for (const char* key : kWallMotionKeys)
        if (block.free_slip && b.has(key))
          b.fail("slip", std::string("\"no\" on a moving wall (") + key + "; free slip is for walls at rest)");
    }
    if (b.has("wetted_face")) {
      // The one face of a dummy-layer box that the fluid wets; fluid beyond its end faces
      // (outside the box along another axis) does not see the block; the sign names the face
      // for the reader and is checked, the rule needs only the axis (vesph/core/pair_loop.hpp WettedFaces, docs/theory.md §6.5).
      if (block.image) b.fail("wetted_face", "no wetted_face with treatment = \"image\" (its normal says which face is wet)");
      if (shape != "box") b.fail("wetted_face", "no wetted_face on a " + shape + " (a box's face)");
      for (const char* key : kWallMotionKeys)
        if (b.has(key)) b.fail("wetted_face", std::string("no wetted_face on a moving wall (") + key + ")");
      std::tie(block.wet_axis, std::ignore) = b.coordinateAxis<D>(
          "wetted_face", "a coordinate unit vector from the wall into the fluid across its wetted face, e.g. [0.0, 1.0] "
                         "for a die's lower wall");
    }
    if (b.has("pressure_floor")) {
      // A wall that pushes but does not pull (at 0): theory.md §6, the die's lip in
      // docs/studies.md §5.
      if (block.image) b.fail("pressure_floor", "no pressure_floor with treatment = \"image\" (dummy layers only)");
      block.pressure_floor = b.number("pressure_floor", std::nullopt, Bound::any, "Pa");
    }
  }

  // frame = "polar": the dummy layers of a round wall average the fluid's velocities and
  // stresses in the polar frame of the block's axis (include/vesph/boundary/dummy_walls.hpp,
  // docs/theory.md §6.3). The axis must stay where it is: a wall at rest or turning about it.
  static void readWallFrame(ConfigTable& b, Block<D>& block, const std::string& shape) {
    block.polar = b.choice("frame", "cartesian", {"cartesian", "polar"}) == "polar";
    if (!block.polar) return;
    const bool round = block.solid.kind == ShapeKind::cylinder || block.solid.kind == ShapeKind::tube ||
                       (D == 2 && block.solid.kind == ShapeKind::ball);
    if (!round)
      b.fail("frame", "\"cartesian\" for a " + shape + " (a polar frame needs an axis: a cylinder or tube" +
                          (D == 2 ? std::string(" or disk") : std::string()) + ")");
    if (block.image) b.fail("frame", "\"cartesian\" with treatment = \"image\" (polar frames are for dummy layers)");
    if (b.has("velocity"))
      b.fail("frame", "\"cartesian\" on a translating wall (the polar frame's axis is fixed: a wall at rest or turning about its own axis)");
    if (!b.has("angular_velocity")) return;
    // Turning: about the block's own axis (the moving walls read and check the motion itself).
    const Vec<D> point = b.has("axis_point") ? b.vector<D>("axis_point", std::nullopt, "m") : block.solid.centre;
    const double size = std::max(block.solid.radius, 1e-300);
    Vec<D> offset = point - block.solid.centre;
    bool about_own_axis = true;
    if constexpr (D == 3) {
      const Vec<3> w = b.vector<3>("angular_velocity", std::nullopt, "rad/s; in 3D the vector omega");
      const double wn = w.norm();
      offset -= offset.dot(block.solid.axis) * block.solid.axis;
      about_own_axis = wn == 0 || (w / wn).cross(block.solid.axis).norm() <= 1e-9;
    }
    if (!about_own_axis || offset.norm() > 1e-9 * size)
      b.fail("frame", "\"cartesian\" on a wall turning about another axis than its own (angular_velocity along the "
                      "block's axis, axis_point on it, for frame = \"polar\")");
  }

  void checkBoxExtent(ConfigTable& b, const Solid<D>& box) const {
    const double dx = g_.spacing;
    for (int a = 0; a < D; ++a) {
      const double L = box.hi[a] - box.lo[a];
      if (!(L > 0)) b.fail("max", "a corner above min along every axis");
      const double cells = L / dx;
      if (std::abs(cells - std::round(cells)) > 1e-6 * std::max(1.0, cells)) {
        std::ostringstream os;
        os << "an extent that is a whole number of particle spacings (" << dx << " m) along axis " << a
           << "; the extent " << L << " m is " << cells << " spacings";
        b.fail("max", os.str());
      }
      const double tol = 1e-9 * g_.domain.length(a);
      if (box.lo[a] < g_.domain.lo[a] - tol || box.hi[a] > g_.domain.hi[a] + tol)
        b.fail("max", "a block inside the domain [domain.min, domain.max]");
    }
  }

  void checkInsideDomain(ConfigTable& b, const Solid<D>& s, const std::string& shape) const {
    for (int a = 0; a < D; ++a) {
      const double tol = 1e-9 * g_.domain.length(a);
      if (s.lo[a] < g_.domain.lo[a] - tol || s.hi[a] > g_.domain.hi[a] + tol)
        b.fail("centre", "a " + shape + " inside the domain [domain.min, domain.max]");
    }
  }

  // A fluid particle next to the wall must see a full kernel of wall particles (thesis §4.2):
  // a box across its thinnest non-periodic extent, a tube across its wall (outer - inner
  // radius), a solid disk / sphere / cylinder across its diameter, a 3D cylinder or tube also
  // along its length unless its axis is a periodic axis of the domain.
  void checkWallThickness(ConfigTable& b, const Solid<D>& s, const std::string& shape) const {
    const double support = g_.kernel.supportRadius();
    const double layers = std::ceil(support / g_.spacing - 1e-9);
    auto refuse = [&](const char* key, const std::string& across, double thinnest) {
      std::ostringstream os;
      os << "a wall at least one kernel support thick (" << support << " m = " << layers << " layers, thesis 4.2) "
         << across << ", which is " << thinnest << " m";
      b.fail(key, os.str());
    };
    if (s.kind == ShapeKind::box) {
      double thinnest = 1e300;
      for (int a = 0; a < D; ++a)
        if (!(g_.domain.periodic[a])) thinnest = std::min(thinnest, s.hi[a] - s.lo[a]);
      if (thinnest < support * (1 - 1e-9)) refuse("max", "across its thinnest non-periodic extent", thinnest);
      return;
    }
    if (s.kind == ShapeKind::tube) {
      const double wall = s.radius - s.inner_radius;
      if (wall < support * (1 - 1e-9)) refuse("outer_diameter", "across the tube's wall (outer - inner radius)", wall);
    } else if (2 * s.radius < support * (1 - 1e-9)) {
      refuse("diameter", "across the " + shape + "'s diameter", 2 * s.radius);
    }
    if constexpr (D == 3)
      if (s.kind != ShapeKind::ball && s.length < support * (1 - 1e-9)) {
        bool periodic_axis = false;
        for (int a = 0; a < D; ++a)
          periodic_axis = periodic_axis || (g_.domain.periodic[a] && std::abs(std::abs(s.axis[a]) - 1) < 1e-12);
        if (!periodic_axis) refuse("length", "along the " + shape + "'s axis", s.length);
      }
  }

  const LatticeGeometry<D>& g_;
  Vec<D> v0_;
};

// The particle count estimated from the blocks' volumes (bounding boxes for curved shapes;
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
    for (int a = 0; a < D; ++a) n *= std::floor((b.solid.hi[a] - b.solid.lo[a]) / g.spacing + 0.5) + 1.0;
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

[[noreturn]] void refuseOverlap(const std::string& file, const std::string& later, const std::string& earlier,
                                const std::string& what) {
  throw InputError(file + ": " + later + ": overlaps " + earlier + ": " + what +
                   " (blocks may touch, not overlap; subtract one shape from the other)");
}

template <int D>
std::string pointText(const double* position, std::size_t i) {
  std::ostringstream os;
  os << "[";
  for (int a = 0; a < D; ++a) os << (a ? ", " : "") << position[D * i + a];
  os << "] m";
  return os.str();
}

// Blocks must not overlap. Two tests on the placed particles (blocks that touch keep their
// particles about a spacing apart, dx/2 on either side of the common surface):
//  * no particle lies inside another block's material (its shape shrunk by dx/4, less its
//    subtracted shapes grown by dx/4): two lattices offset by half a spacing interleave at
//    dx/2 without coming closer;
//  * no two particles of different blocks closer than dx/2: particles are binned on a grid of
//    cells at least dx wide (counting sort, O(N)), so such a pair lies in the same or adjacent
//    cells; periodic axes wrap.
template <int D>
void checkOverlaps(const ParticleSet<D>& particles, const std::vector<double>& displacement,
                   const std::vector<BlockParticles>& spans, const std::vector<Block<D>>& blocks,
                   const LatticeGeometry<D>& g) {
  const std::size_t n = particles.size();
  if (n == 0) return;
  // The lattice positions (before any jitter), in a copy only when a block jitters.
  std::vector<double> lattice;
  if (!displacement.empty()) {
    lattice = particles.position;
    for (std::size_t k = 0; k < lattice.size(); ++k) lattice[k] -= displacement[k];
  }
  const double* position = lattice.empty() ? particles.position.data() : lattice.data();
  std::vector<std::uint32_t> owner(n, 0);
  for (std::size_t k = 0; k < spans.size(); ++k)
    std::fill(owner.begin() + static_cast<std::ptrdiff_t>(spans[k].first),
              owner.begin() + static_cast<std::ptrdiff_t>(spans[k].first + spans[k].count), static_cast<std::uint32_t>(k));
  const double quarter = 0.25 * g.spacing;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec<D> x = Eigen::Map<const Vec<D>>(position + D * i);
    for (std::size_t m = 0; m < blocks.size(); ++m)
      if (m != owner[i] && blocks[m].solid.contains(x, -quarter) && !blocks[m].removed(x, quarter)) {
        const std::size_t first = std::min<std::size_t>(m, owner[i]), second = std::max<std::size_t>(m, owner[i]);
        refuseOverlap(g.file, blocks[second].path, blocks[first].path,
                      "a particle of " + blocks[owner[i]].path + " at " + pointText<D>(position, i) + " lies inside " +
                          blocks[m].path + "'s shape");
      }
  }
  Vec<D> lo, hi;
  for (int a = 0; a < D; ++a) {
    lo[a] = g.domain.periodic[a] ? g.domain.lo[a] : 1e300;
    hi[a] = g.domain.periodic[a] ? g.domain.hi[a] : -1e300;
  }
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < D; ++a)
      if (!g.domain.periodic[a]) {
        lo[a] = std::min(lo[a], position[D * i + a]);
        hi[a] = std::max(hi[a], position[D * i + a]);
      }
  // Cells of side dx, widened when the particles' bounding box would need more than ~8 cells
  // per particle (a drop far above its floor).
  double cell = g.spacing, cells = 1;
  for (int a = 0; a < D; ++a) cells *= (hi[a] - lo[a]) / cell + 1;
  if (cells > 8.0 * static_cast<double>(n)) cell *= std::pow(cells / (8.0 * static_cast<double>(n)), 1.0 / D);
  std::array<long, D> dims;
  std::size_t total = 1;
  for (int a = 0; a < D; ++a) {
    dims[a] = std::max(1L, static_cast<long>(std::floor((hi[a] - lo[a]) / cell)) + 1);
    total *= static_cast<std::size_t>(dims[a]);
  }
  auto coord = [&](std::size_t i, int a) {
    return std::clamp(static_cast<long>(std::floor((position[D * i + a] - lo[a]) / cell)), 0L, dims[a] - 1);
  };
  auto linear = [&](const std::array<long, D>& c) {
    std::size_t k = 0;
    for (int a = D - 1; a >= 0; --a) k = k * static_cast<std::size_t>(dims[a]) + static_cast<std::size_t>(c[a]);
    return k;
  };
  std::vector<std::size_t> start(total + 1, 0), order(n);
  std::vector<std::size_t> cell_of(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::array<long, D> c;
    for (int a = 0; a < D; ++a) c[a] = coord(i, a);
    cell_of[i] = linear(c);
    ++start[cell_of[i] + 1];
  }
  for (std::size_t k = 0; k < total; ++k) start[k + 1] += start[k];
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order[fill[cell_of[i]]++] = i;
  }
  const double reach2 = 0.25 * g.spacing * g.spacing * (1 - 1e-9);
  for (std::size_t i = 0; i < n; ++i) {
    std::array<long, D> base;
    for (int a = 0; a < D; ++a) base[a] = coord(i, a);
    std::array<int, D> step;
    step.fill(-1);
    while (true) {
      std::array<long, D> c;
      bool valid = true;
      for (int a = 0; a < D; ++a) {
        c[a] = base[a] + step[a];
        if (c[a] < 0 || c[a] >= dims[a]) {
          if (g.domain.periodic[a]) c[a] = (c[a] + dims[a]) % dims[a];
          else valid = false;
        }
      }
      if (valid) {
        const std::size_t k = linear(c);
        for (std::size_t m = start[k]; m < start[k + 1]; ++m) {
          const std::size_t j = order[m];
          if (owner[j] == owner[i]) continue;
          double r2 = 0;
          for (int a = 0; a < D; ++a) {
            const double d = g.domain.image(a, position[D * i + a] - position[D * j + a]);
            r2 += d * d;
          }
          if (r2 < reach2) {
            const std::size_t first = std::min(owner[i], owner[j]), second = std::max(owner[i], owner[j]);
            std::ostringstream os;
            os << "particles of the two blocks closer than half a spacing (" << std::sqrt(r2) << " m < "
               << 0.5 * g.spacing << " m), one at " << pointText<D>(position, owner[i] == second ? i : j);
            refuseOverlap(g.file, blocks[second].path, blocks[first].path, os.str());
          }
        }
      }
      int a = 0;
      while (a < D && ++step[a] > 1) step[a++] = -1;
      if (a == D) break;
    }
  }
}

// Places the particles of the blocks, fluid blocks first, with consecutive ids.
template <int D>
class LatticePlacer {
 public:
  LatticePlacer(const LatticeGeometry<D>& g, ParticleSet<D>& p, std::vector<WallPoint<D>>& wall_points)
      : g_(g), p_(p), wall_points_(wall_points), mass_(g.rest_density * std::pow(g.spacing, D)) {}

  void place(const std::vector<Block<D>>& blocks, std::vector<HydrostaticBlock<D>>* hydrostatic,
             std::vector<BlockParticles>& spans) {
    spans.assign(blocks.size(), BlockParticles{});
    for (ParticleKind pass : {ParticleKind::fluid, ParticleKind::wall})
      for (std::size_t k = 0; k < blocks.size(); ++k) {
        const Block<D>& b = blocks[k];
        if (b.kind != pass) continue;
        const std::size_t first = p_.size();
        if (b.solid.kind == ShapeKind::ball && b.kind == ParticleKind::wall && D == 3) placeShells(b);
        else if (b.rings()) placeRings(b);
        else if (b.solid.kind == ShapeKind::ball) placeRound(b);
        else placeBox(b, pass);
        if (b.hydrostatic && hydrostatic)
          hydrostatic->push_back({first, p_.size(), b.solid.lo, b.solid.hi, b.surface_height, b.path});
        spans[k] = BlockParticles{first, p_.size() - first, pass == ParticleKind::wall, b.image};
        if (p_.size() == first)
          throw InputError(g_.file + ": " + b.path + ": no particles left (its subtracted shapes cover it)");
      }
  }

  // Per particle its random displacement (D values; empty when no block jitters): the overlap
  // check looks at the lattice, the positions less these.
  const std::vector<double>& displacements() const { return displacement_; }

 private:
  void add(const Vec<D>& x, const Block<D>& b, ParticleKind kind, double mass) {
    if (kind == ParticleKind::wall && !b.image) {
      WallPoint<D> w;
      w.pressure_floor = b.pressure_floor;
      w.linear_stress = b.linear_stress;
      w.free_slip = b.free_slip;
      if (b.wet_axis >= 0) {
        w.wetted_axis = b.wet_axis;
        w.box_lo = b.solid.lo;
        w.box_hi = b.solid.hi;
      }
      if (b.polar) {
        w.polar = true;
        w.axis_point = b.solid.centre;
        w.axis = b.solid.axis;
      }
      wall_points_.push_back(w);
    }
    const Vec<D> d = jitter(b);
    if (b.jitter > 0 && displacement_.empty()) displacement_.assign(D * p_.size(), 0.0);
    if (!displacement_.empty()) displacement_.insert(displacement_.end(), d.data(), d.data() + D);
    p_.add(Vec<D>(x + d), b.velocity, g_.rest_density, mass, kind, next_id_++);
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

  // Subtracted shapes remove the particles inside them or on their surface.
  double slack() const { return 1e-9 * g_.spacing; }

  void placeRound(const Block<D>& b) {
    const double dx = g_.spacing;
    const long reach = static_cast<long>(std::floor(b.solid.radius / dx + 1e-9));
    const double r2max = b.solid.radius * b.solid.radius * (1 + 1e-12);
    std::array<long, D> k;
    k.fill(-reach);
    while (true) {
      Vec<D> off;
      for (int a = 0; a < D; ++a) off[a] = static_cast<double>(k[a]) * dx;
      const Vec<D> x = b.solid.centre + off;
      if (off.squaredNorm() <= r2max && !b.removed(x, slack())) add(x, b, ParticleKind::fluid, mass_);
      int a = 0;
      while (a < D && ++k[a] > reach) k[a++] = -reach;
      if (a == D) break;
    }
  }

  // Two unit vectors normal to the unit axis e and to each other (3D).
  static std::pair<Vec<D>, Vec<D>> transverse(const Vec<D>& e) {
    Vec<D> u = Vec<D>::Zero(), v = Vec<D>::Zero();
    if constexpr (D == 3) {
      int least = 0;
      for (int a = 1; a < 3; ++a)
        if (std::abs(e[a]) < std::abs(e[least])) least = a;
      Vec<D> t = Vec<D>::Zero();
      t[least] = 1;
      u = (t - t.dot(e) * e).normalized();
      v = Vec<D>(e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0]);
    } else {
      u[0] = 1;
      v[1] = 1;
    }
    return {u, v};
  }

  // Cylinders, tubes and 2D wall disks: n_r = round((R - R_i)/dx) rings of width
  // dr = (R - R_i)/n_r at radii r_k = R_i + (k + 1/2) dr, each with N_k = round(2 pi r_k / dx)
  // particles at equal angles (every other ring turned by half a step), in 3D stacked at
  // n_z = round(L/dx) stations dz = L/n_z apart along the axis. Mass rho0 * 2 pi r_k dr (dz) / N_k:
  // the ring cells tile the shape, so the summed volume is the analytic one (docs/theory.md §6.3).
  void placeRings(const Block<D>& b) {
    const Solid<D>& s = b.solid;
    const double dx = g_.spacing, pi = std::numbers::pi;
    const double inner = s.kind == ShapeKind::tube ? s.inner_radius : 0.0;
    const long n_r = std::max(1L, std::lround((s.radius - inner) / dx));
    const double dr = (s.radius - inner) / static_cast<double>(n_r);
    long n_z = 1;
    double dz = 1;
    if constexpr (D == 3) {
      n_z = std::max(1L, std::lround(s.length / dx));
      dz = s.length / static_cast<double>(n_z);
    }
    const auto [u, v] = transverse(s.axis);
    for (long j = 0; j < n_z; ++j) {
      Vec<D> station = s.centre;
      if constexpr (D == 3) station += (-0.5 * s.length + (static_cast<double>(j) + 0.5) * dz) * s.axis;
      for (long k = 0; k < n_r; ++k) {
        const double r = inner + (static_cast<double>(k) + 0.5) * dr;
        const long count = std::max(1L, std::lround(2 * pi * r / dx));
        const double step = 2 * pi / static_cast<double>(count);
        const double phase = (k % 2) * 0.5 * step;
        const double mass = g_.rest_density * 2 * pi * r * dr * (D == 3 ? dz : 1.0) / static_cast<double>(count);
        for (long i = 0; i < count; ++i) {
          const double theta = phase + step * static_cast<double>(i);
          const Vec<D> x = station + r * (std::cos(theta) * u + std::sin(theta) * v);
          if (!b.removed(x, slack())) add(x, b, b.kind, mass);
        }
      }
    }
  }

  // Sphere walls: n_r = round(R/dx) shells of width dr = R/n_r at r_k = (k + 1/2) dr, each with
  // N_k = round(4 pi r_k^2 / dx^2) particles on a Fibonacci lattice (near-uniform on the sphere),
  // mass rho0 * (shell volume) / N_k.
  void placeShells(const Block<D>& b) {
    if constexpr (D == 3) {
      const Solid<D>& s = b.solid;
      const double dx = g_.spacing, pi = std::numbers::pi;
      const double golden = pi * (3.0 - std::sqrt(5.0));
      const long n_r = std::max(1L, std::lround(s.radius / dx));
      const double dr = s.radius / static_cast<double>(n_r);
      for (long k = 0; k < n_r; ++k) {
        const double r = (static_cast<double>(k) + 0.5) * dr, r_in = r - 0.5 * dr, r_out = r + 0.5 * dr;
        const long count = std::max(1L, std::lround(4 * pi * r * r / (dx * dx)));
        const double mass = g_.rest_density * 4.0 / 3.0 * pi * (r_out * r_out * r_out - r_in * r_in * r_in) /
                            static_cast<double>(count);
        for (long i = 0; i < count; ++i) {
          const double z = 1.0 - (2.0 * static_cast<double>(i) + 1.0) / static_cast<double>(count);
          const double rho = std::sqrt(std::max(0.0, 1.0 - z * z)), phi = golden * static_cast<double>(i) + k;
          const Vec<D> x = s.centre + r * Vec<D>(rho * std::cos(phi), rho * std::sin(phi), z);
          if (!b.removed(x, slack())) add(x, b, ParticleKind::wall, mass);
        }
      }
    } else {
      (void)b;
    }
  }

  void placeBox(const Block<D>& b, ParticleKind pass) {
    const double dx = g_.spacing;
    std::array<long, D> n;
    long total = 1;
    for (int a = 0; a < D; ++a) {
      n[a] = std::lround((b.solid.hi[a] - b.solid.lo[a]) / dx);
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
        x[a] = b.solid.lo[a] + (static_cast<double>(idx[a]) + 0.5) * dx;
        rem /= n[a];
      }
      if (b.image) {
        const int a = b.normal_axis;
        const double surface = b.normal_sign > 0 ? b.solid.hi[a] : b.solid.lo[a];
        x[a] = surface - b.normal_sign * static_cast<double>(idx[a]) * dx;
        wall_points_.push_back(imagePoint(b, idx, n, first));
      } else if (b.removed(x, slack())) {
        continue;
      }
      add(x, b, pass, mass_);
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
  std::vector<double> displacement_;
};

// The analytic volume of a block: its shape's, less per subtracted shape the part inside the
// block: the subtracted shape's analytic volume when it lies wholly inside (every node of a
// lattice of spacing dx/4 over its bounding box that it contains is in the block), NaN when it
// cuts across the block's surface (subtracted shapes are taken as disjoint).
template <int D>
double referenceVolume(const Block<D>& b, double dx) {
  double volume = b.solid.volume();
  for (const Solid<D>& s : b.subtract) {
    double h = 0.25 * dx, nodes = 1;
    for (int a = 0; a < D; ++a) nodes *= (s.hi[a] - s.lo[a]) / h + 1;
    if (nodes > 4e6) h *= std::pow(nodes / 4e6, 1.0 / D);
    std::array<long, D> n, k;
    for (int a = 0; a < D; ++a) n[a] = static_cast<long>(std::floor((s.hi[a] - s.lo[a]) / h)) + 1;
    k.fill(0);
    bool inside = false, outside = false;
    while (true) {
      Vec<D> x;
      for (int a = 0; a < D; ++a) x[a] = s.lo[a] + static_cast<double>(k[a]) * h;
      if (s.contains(x, 0)) {
        if (b.solid.contains(x, 0)) inside = true;
        else outside = true;
      }
      int a = 0;
      while (a < D && ++k[a] >= n[a]) k[a++] = 0;
      if (a == D) break;
    }
    if (inside && outside) return std::numeric_limits<double>::quiet_NaN();
    if (inside) volume -= s.volume();
  }
  return volume;
}

const char* kindName(ParticleKind k) { return k == ParticleKind::fluid ? "fluid" : "wall"; }

}  // namespace

template <int D>
std::vector<WallPoint<D>> generateParticles(ConfigTable& root, const LatticeGeometry<D>& geometry,
                                            ParticleSet<D>& particles, std::vector<HydrostaticBlock<D>>* hydrostatic,
                                            std::vector<BlockParticles>* spans, std::vector<BlockSummary>* summaries) {
  const Vec<D> v0 = root.table("initial").vector<D>("velocity", Vec<D>::Zero(), "m/s");
  auto tables = root.tableArray("blocks");
  if (tables.empty()) root.fail("blocks", "at least one [[blocks]] table with kind, min and max");
  const BlockReader<D> reader(geometry, v0);
  std::vector<Block<D>> blocks;
  for (ConfigTable& b : tables) blocks.push_back(reader.read(b));
  checkParticleCount(blocks, geometry);

  std::vector<WallPoint<D>> wall_points;
  if (!hydrostatic)
    for (const Block<D>& b : blocks)
      if (b.hydrostatic) throw InputError(geometry.file + ": " + b.path + ".hydrostatic: not available here");
  std::vector<BlockParticles> own_spans;
  std::vector<BlockParticles>& block_spans = spans ? *spans : own_spans;
  LatticePlacer<D> placer(geometry, particles, wall_points);
  placer.place(blocks, hydrostatic, block_spans);
  checkOverlaps(particles, placer.displacements(), block_spans, blocks, geometry);
  if (particles.n_moving == 0) root.fail("blocks", "at least one block of kind \"fluid\"");
  if (summaries) {
    summaries->clear();
    for (std::size_t k = 0; k < blocks.size(); ++k) {
      BlockSummary s{blocks[k].path, kindName(blocks[k].kind), blocks[k].shape_name, block_spans[k].count, 0.0,
                     referenceVolume(blocks[k], geometry.spacing)};
      for (std::size_t i = block_spans[k].first; i < block_spans[k].first + block_spans[k].count; ++i)
        s.volume += particles.mass[i] / geometry.rest_density;
      if (blocks[k].image) s.reference_volume = std::numeric_limits<double>::quiet_NaN();  // boundary rows extra
      summaries->push_back(s);
    }
  }
  // Scenes without image walls, pressure floors, polar frames, linear stresses, free slip or wetted faces keep no per-wall-particle
  // record (DummyWalls treats an empty one as all no-slip dummy layers without a floor).
  if (std::none_of(wall_points.begin(), wall_points.end(), [](const WallPoint<D>& w) {
        return w.image || w.polar || w.linear_stress || w.free_slip || std::isfinite(w.pressure_floor) ||
               w.wetted_axis >= 0;
      }))
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
                                                        std::vector<HydrostaticBlock<2>>*, std::vector<BlockParticles>*,
                                                        std::vector<BlockSummary>*);
template std::vector<WallPoint<3>> generateParticles<3>(ConfigTable&, const LatticeGeometry<3>&, ParticleSet<3>&,
                                                        std::vector<HydrostaticBlock<3>>*, std::vector<BlockParticles>*,
                                                        std::vector<BlockSummary>*);
template void applyHydrostaticDensity<2>(const std::vector<HydrostaticBlock<2>>&, const PressureModel*, const Vec<2>&,
                                         double, const std::string&, ParticleSet<2>&);
template void applyHydrostaticDensity<3>(const std::vector<HydrostaticBlock<3>>&, const PressureModel*, const Vec<3>&,
                                         double, const std::string&, ParticleSet<3>&);
template void markWallLayers<2>(ParticleSet<2>&, const NeighbourList<2>&, const Domain<2>&, double);
template void markWallLayers<3>(ParticleSet<3>&, const NeighbourList<3>&, const Domain<3>&, double);

}  // namespace vesph
