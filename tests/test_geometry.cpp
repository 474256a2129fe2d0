// Scene geometry (src/sim/particle_generation.cpp, docs/user-guide.md "[[blocks]]"): every
// shape in 2D and 3D, fluid and wall, with and without subtracted shapes, holds the shape's
// volume within 1 % (summed m/rho0); rings keep a spacing near dx; overlapping blocks, thin
// curved walls and 2D cylinder axes are refused; moving curved walls turn rigidly.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "vesph/sim/simulation.hpp"

using namespace vesph;

namespace {

constexpr double kPi = std::numbers::pi;

Vec<3> cross(const Vec<3>& a, const Vec<3>& b) {
  return Vec<3>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

// A scene at rest, dx = 1e-4 m, quintic kernel with h = 1.6 dx (support 4.8 dx), the blocks given;
// the domain [-4, 4] mm in 2D, [-2, 2] mm in 3D.
std::string scene(int dimension, const std::string& blocks, const std::string& periodic = "") {
  const std::string lo = dimension == 2 ? "[-4e-3, -4e-3]" : "[-2e-3, -2e-3, -2e-3]";
  const std::string hi = dimension == 2 ? "[4e-3, 4e-3]" : "[2e-3, 2e-3, 2e-3]";
  return "name = \"geometry\"\ndimension = " + std::to_string(dimension) + "\n[domain]\nmin = " + lo + "\nmax = " + hi +
         "\n" + periodic + "\n[particles]\nspacing = 1e-4\nkernel = \"quintic\"\nsmoothing_ratio = 1.6\n"
         "[fluid]\ndensity = 1000.0\nviscosity = 1e-3\n" + blocks +
         "\n[effects.continuity]\n[effects.equation_of_state]\nsound_speed = 1.0\n[effects.pressure_gradient]\n"
         "[effects.viscosity]\n[time]\nend = 1e-3\n";
}

template <int D>
std::vector<BlockSummary> summaries(const std::string& text) {
  Config cfg = Config::fromString(text, "geometry.toml");
  SceneHeader h{"geometry", D};
  Simulation<D> sim(cfg, h);
  return sim.blockSummaries();
}

template <int D>
std::string buildError(const std::string& text) {
  try {
    Config cfg = Config::fromString(text, "geometry.toml");
    SceneHeader h{"geometry", D};
    Simulation<D> sim(cfg, h);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void checkVolume(const BlockSummary& b, double analytic) {
  CAPTURE(b.path);
  CAPTURE(b.shape);
  CHECK(b.count > 0);
  CHECK(b.reference_volume == doctest::Approx(analytic).epsilon(1e-9));
  CHECK(std::abs(b.volume / analytic - 1.0) < 0.01);
}

}  // namespace

TEST_CASE("geometry: every 2D shape holds its area within 1 % (fluid and wall, with subtractions)") {
  // A fluid cylinder (rings) of diameter 1 mm, a wall tube around it, a fluid disk (the
  // Cartesian cut, 15 dx in radius: the cut is within 1 % from about 10 dx), a wall box with a
  // round hole, a wall disk (rings).
  const std::string blocks = R"(
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [-1.0e-3, -1.0e-3]
diameter = 1.0e-3
[[blocks]]
kind = "wall"
shape = "tube"
centre = [-1.0e-3, -1.0e-3]
inner_diameter = 1.0e-3
outer_diameter = 2.0e-3
[[blocks]]
kind = "fluid"
shape = "disk"
centre = [2.0e-3, -2.0e-3]
diameter = 3.0e-3
[[blocks]]
kind = "wall"
min = [0.2e-3, 0.2e-3]
max = [3.8e-3, 3.8e-3]
subtract = [ { shape = "disk", centre = [2.0e-3, 2.0e-3], diameter = 1.0e-3 } ]
[[blocks]]
kind = "wall"
shape = "disk"
centre = [-1.0e-3, 1.0e-3]
diameter = 1.0e-3
)";
  const auto s = summaries<2>(scene(2, blocks));
  REQUIRE(s.size() == 5);
  checkVolume(s[0], kPi * 0.25e-6);
  CHECK(s[0].volume == doctest::Approx(kPi * 0.25e-6).epsilon(1e-12));  // rings tile the disk exactly
  checkVolume(s[1], kPi * (1.0e-6 - 0.25e-6));
  checkVolume(s[2], kPi * 2.25e-6);
  checkVolume(s[3], 3.6e-3 * 3.6e-3 - kPi * 0.25e-6);
  checkVolume(s[4], kPi * 0.25e-6);
  // The tube's rings: dr = dx, ring k of radius (k + 1/2) dr with round(2 pi r / dx) particles.
  std::size_t count = 0;
  for (int k = 0; k < 5; ++k) count += static_cast<std::size_t>(std::lround(2 * kPi * (0.5e-3 + (k + 0.5) * 1e-4) / 1e-4));
  CHECK(s[1].count == count);

  // The Cartesian cut of a coarse disk (7 dx in radius) misses by 3.2 %: the summary shows it.
  const auto coarse = summaries<2>(scene(2, "[[blocks]]\nkind = \"fluid\"\nshape = \"disk\"\ncentre = [0.0, 0.0]\n"
                                            "diameter = 1.4e-3\n"));
  CHECK(coarse[0].volume / coarse[0].reference_volume - 1 == doctest::Approx(-0.0321).epsilon(0.01));

  // A tube of fluid with a box cut across its ring: the box's part inside has no analytic
  // value; the summary says so (NaN) and the count drops.
  const std::string cut = R"(
[[blocks]]
kind = "fluid"
shape = "tube"
centre = [0.0, 0.0]
inner_diameter = 1.0e-3
outer_diameter = 2.0e-3
subtract = [ { shape = "box", min = [-1.5e-3, -0.2e-3], max = [0.0, 0.2e-3] } ]
)";
  const auto c = summaries<2>(scene(2, cut));
  CHECK(std::isnan(c[0].reference_volume));
  CHECK(c[0].volume < kPi * 0.75e-6 * 0.97);
}

TEST_CASE("geometry: every 3D shape holds its volume within 1 % (any axis, with subtractions)") {
  const std::string blocks = R"(
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [-1.0e-3, -1.0e-3, 0.0]
diameter = 0.8e-3
axis = [0.0, 0.0, 1.0]
length = 2.0e-3
[[blocks]]
kind = "wall"
shape = "tube"
centre = [-1.0e-3, -1.0e-3, 0.0]
inner_diameter = 0.8e-3
outer_diameter = 1.8e-3
axis = [0.0, 0.0, 2.0]
length = 2.0e-3
[[blocks]]
kind = "fluid"
shape = "sphere"
centre = [1.0e-3, -1.0e-3, -1.0e-3]
diameter = 1.8e-3
[[blocks]]
kind = "wall"
shape = "sphere"
centre = [1.0e-3, -1.0e-3, 1.0e-3]
diameter = 1.2e-3
[[blocks]]
kind = "wall"
shape = "cylinder"
centre = [0.0, 1.0e-3, 0.0]
diameter = 0.8e-3
axis = [1.0, 1.0, 1.0]
length = 1.5e-3
[[blocks]]
kind = "wall"
min = [-1.8e-3, 0.2e-3, -1.8e-3]
max = [-0.6e-3, 1.8e-3, -0.6e-3]
subtract = [ { shape = "cylinder", centre = [-1.2e-3, 1.0e-3, -1.2e-3], diameter = 0.4e-3, axis = [0.0, 1.0, 0.0], length = 1.0e-3 } ]
)";
  const auto s = summaries<3>(scene(3, blocks));
  REQUIRE(s.size() == 6);
  checkVolume(s[0], kPi * 0.16e-6 * 2e-3);
  checkVolume(s[1], kPi * (0.81e-6 - 0.16e-6) * 2e-3);
  checkVolume(s[2], 4.0 / 3.0 * kPi * 0.729e-9);  // the Cartesian cut, 9 dx in radius
  checkVolume(s[3], 4.0 / 3.0 * kPi * 0.216e-9);
  CHECK(s[3].volume == doctest::Approx(4.0 / 3.0 * kPi * 0.216e-9).epsilon(1e-12));  // shells tile the ball
  checkVolume(s[4], kPi * 0.16e-6 * 1.5e-3);
  checkVolume(s[5], 1.2e-3 * 1.6e-3 * 1.2e-3 - kPi * 0.04e-6 * 1.0e-3);
}

TEST_CASE("geometry: a periodic pipe (tube wall, fluid cylinder along a periodic axis)") {
  const std::string blocks = R"(
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [0.0, 0.0, 0.0]
diameter = 1.0e-3
axis = [0.0, 0.0, 1.0]
length = 4.0e-3
[[blocks]]
kind = "wall"
shape = "tube"
centre = [0.0, 0.0, 0.0]
inner_diameter = 1.0e-3
outer_diameter = 2.0e-3
axis = [0.0, 0.0, 1.0]
length = 4.0e-3
)";
  const auto s = summaries<3>(scene(3, blocks, "periodic = [false, false, true]"));
  checkVolume(s[0], kPi * 0.25e-6 * 4e-3);
  checkVolume(s[1], kPi * 0.75e-6 * 4e-3);
}

TEST_CASE("geometry: refusals name the key (overlap, thin curved wall, 2D axis, bad subtraction)") {
  const std::string fluid = "[[blocks]]\nkind = \"fluid\"\nshape = \"cylinder\"\ncentre = [0.0, 0.0]\ndiameter = 1.0e-3\n";
  // A wall tube whose inner radius cuts into the fluid cylinder.
  std::string e = buildError<2>(scene(2, fluid + "[[blocks]]\nkind = \"wall\"\nshape = \"tube\"\ncentre = [0.0, 0.0]\n"
                                                 "inner_diameter = 0.8e-3\nouter_diameter = 2.0e-3\n"));
  CHECK(e.find("blocks[1]: overlaps blocks[0]") != std::string::npos);
  // Touching is fine (the same tube from the fluid's radius out), as is a box beside it.
  CHECK(buildError<2>(scene(2, fluid + "[[blocks]]\nkind = \"wall\"\nshape = \"tube\"\ncentre = [0.0, 0.0]\n"
                                       "inner_diameter = 1.0e-3\nouter_diameter = 2.0e-3\n")) == "");
  // A tube wall thinner than the kernel support (4.8 dx).
  e = buildError<2>(scene(2, fluid + "[[blocks]]\nkind = \"wall\"\nshape = \"tube\"\ncentre = [0.0, 0.0]\n"
                                     "inner_diameter = 1.0e-3\nouter_diameter = 1.6e-3\n"));
  CHECK(e.find("blocks[1].outer_diameter: expected a wall at least one kernel support thick") != std::string::npos);
  // A 2D cylinder is its cross-section.
  e = buildError<2>(scene(2, fluid + "axis = [1.0, 0.0]\n"));
  CHECK(e.find("blocks[0].axis: expected no axis in 2D") != std::string::npos);
  // 3D: the axis and length are required; a zero axis is refused.
  const std::string f3 = "[[blocks]]\nkind = \"fluid\"\nshape = \"cylinder\"\ncentre = [0.0, 0.0, 0.0]\ndiameter = 1.0e-3\n";
  CHECK(buildError<3>(scene(3, f3 + "length = 1e-3\n")).find("blocks[0].axis") != std::string::npos);
  CHECK(buildError<3>(scene(3, f3 + "axis = [0.0, 0.0, 0.0]\nlength = 1e-3\n")).find("non-zero") != std::string::npos);
  CHECK(buildError<3>(scene(3, f3 + "axis = [0.0, 0.0, 1.0]\n")).find("blocks[0].length") != std::string::npos);
  // A subtracted shape with an unknown key or a bad size.
  e = buildError<2>(scene(2, fluid + "subtract = [ { shape = \"disk\", centre = [0.0, 0.0], diameter = -1.0 } ]\n"));
  CHECK(e.find("blocks[0].subtract[0].diameter") != std::string::npos);
  e = buildError<2>(scene(2, fluid + "subtract = [ { shape = \"disk\", centre = [0.0, 0.0], radius = 1.0 } ]\n"));
  CHECK(e.find("blocks[0].subtract[0].diameter") != std::string::npos);
  // A shape outside the domain.
  e = buildError<2>(scene(2, "[[blocks]]\nkind = \"fluid\"\nshape = \"tube\"\ncentre = [3.5e-3, 0.0]\n"
                             "inner_diameter = 1.0e-3\nouter_diameter = 2.0e-3\n"));
  CHECK(e.find("blocks[0].centre: expected a tube inside the domain") != std::string::npos);
}

TEST_CASE("geometry: rings keep their neighbours about dx apart (no clumps at any radius)") {
  const std::string blocks = R"(
[[blocks]]
kind = "fluid"
shape = "cylinder"
centre = [0.0, 0.0]
diameter = 2.0e-3
)";
  Config cfg = Config::fromString(scene(2, blocks), "geometry.toml");
  SceneHeader h{"geometry", 2};
  Simulation<2> sim(cfg, h);
  const auto& p = sim.system().particles;
  // Nearest-neighbour distance of every particle (brute force, ~300 particles).
  double closest = 1e9, farthest = 0;
  for (std::size_t i = 0; i < p.n_moving; ++i) {
    double nearest = 1e9;
    for (std::size_t j = 0; j < p.n_moving; ++j)
      if (j != i) nearest = std::min(nearest, (Vec<2>(p.x(i)) - Vec<2>(p.x(j))).norm());
    closest = std::min(closest, nearest);
    farthest = std::max(farthest, nearest);
  }
  CHECK(closest > 0.8e-4);
  CHECK(farthest < 1.1e-4);
}

TEST_CASE("geometry: curved walls turning about an oblique 3D axis mirror a fluid in solid-body rotation") {
  // A fluid tube between a wall cylinder and a wall tube, all three about the axis e = (1,1,1)/sqrt 3,
  // both walls turning at omega = 4 e rad/s about the origin. With the fluid's velocity the rigid
  // field omega x x, each wall particle's ghost velocity is its own rigid velocity (docs/theory.md
  // §6.2, the mirror relative to the rigid motion), and the walls sit at R(omega t) x0 (Rodrigues).
  const std::string blocks = R"(
[[blocks]]
kind = "fluid"
shape = "tube"
centre = [0.0, 0.0, 0.0]
inner_diameter = 1.0e-3
outer_diameter = 1.6e-3
axis = [1.0, 1.0, 1.0]
length = 1.0e-3
[[blocks]]
kind = "wall"
shape = "cylinder"
centre = [0.0, 0.0, 0.0]
diameter = 1.0e-3
axis = [1.0, 1.0, 1.0]
length = 1.0e-3
angular_velocity = [2.309401076758503, 2.309401076758503, 2.309401076758503]
axis_point = [0.0, 0.0, 0.0]
[[blocks]]
kind = "wall"
shape = "tube"
centre = [0.0, 0.0, 0.0]
inner_diameter = 1.6e-3
outer_diameter = 2.6e-3
axis = [1.0, 1.0, 1.0]
length = 1.0e-3
angular_velocity = [2.309401076758503, 2.309401076758503, 2.309401076758503]
axis_point = [0.0, 0.0, 0.0]
)";
  Config cfg = Config::fromString(scene(3, blocks), "geometry.toml");
  SceneHeader h{"geometry", 3};
  Simulation<3> sim(cfg, h);
  SphSystem<3>& sys = sim.system();
  ParticleSet<3>& P = sys.particles;
  const std::size_t n = P.n_moving;
  const std::vector<double> x0(P.position.begin() + 3 * n, P.position.end());
  const Vec<3> omega = Vec<3>::Constant(2.309401076758503);
  std::vector<double> y = sim.state(), ydot(y.size());
  for (std::size_t i = 0; i < n; ++i) {  // velocities after positions (3n) and densities (n)
    const Vec<3> v = cross(omega, Vec<3>(y[3 * i], y[3 * i + 1], y[3 * i + 2]));
    for (int a = 0; a < 3; ++a) y[4 * n + 3 * i + a] = v[a];
  }
  const double t = 0.1;
  sys.evaluate(t, y.data(), ydot.data());
  const Vec<3> e = omega.normalized();
  const double theta = omega.norm() * t, c = std::cos(theta), s = std::sin(theta);
  const Field* ghost = P.fields.find("wall_velocity");
  REQUIRE(ghost != nullptr);
  double err_x = 0, err_ghost = 0, speed = 0;
  std::size_t touching = 0;
  for (std::size_t k = 0; k < P.nFixed(); ++k) {
    const Vec<3> r0(x0[3 * k], x0[3 * k + 1], x0[3 * k + 2]);
    const Vec<3> turned = r0 * c + cross(e, r0) * s + e * (e.dot(r0) * (1 - c));
    const std::size_t w = n + k;
    const Vec<3> xw(P.position[3 * w], P.position[3 * w + 1], P.position[3 * w + 2]);
    err_x = std::max(err_x, (xw - turned).norm());
    const Vec<3> rigid = cross(omega, xw);
    speed = std::max(speed, rigid.norm());
    if (P.kind[w] != static_cast<std::uint8_t>(ParticleKind::wall)) continue;  // no fluid within 1.5 dx
    ++touching;
    err_ghost = std::max(err_ghost, (Vec<3>(ghost->data[3 * k], ghost->data[3 * k + 1], ghost->data[3 * k + 2]) - rigid).norm());
  }
  CHECK(touching > 500);  // the wall rings within 1.5 dx of the fluid (810)
  CHECK(err_x < 1e-17);
  CHECK(speed > 4e-3);
  CHECK(err_ghost < 1e-14 * speed / 4e-3 * 10);
}
