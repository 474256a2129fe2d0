// Moving walls (src/boundary/moving_walls.cpp, docs/theory.md §6.2): the prescribed motion as an
// exact function of time, the no-slip mirror of a translating and of a rotating wall, the
// implicit part's Jacobian-vector product (the wall velocity in b(x), not in J), the input checks.
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "vesph/boundary/moving_walls.hpp"
#include "vesph/sim/simulation.hpp"
#include "vesph/sim/system.hpp"

using namespace vesph;

namespace {

const char* kCouette = VESPH_SOURCE_DIR "/cases/couette_startup.toml";
const char* kBox = VESPH_SOURCE_DIR "/cases/rotating_box.toml";
const char* kBox3 = VESPH_SOURCE_DIR "/tests/scenes/rotating_box_3d.toml";

template <int D>
std::unique_ptr<Simulation<D>> build(Config& cfg, SceneHeader& h) {
  return std::make_unique<Simulation<D>>(cfg, h);
}

}  // namespace

TEST_CASE("moving walls: the motion's position, velocity and acceleration agree (2D and 3D, ramped)") {
  WallMotion<2> m2;
  m2.velocity = Vec<2>(0.3, -0.1);
  m2.angular_velocity = Vec<3>(0, 0, 2.5);
  m2.axis_point = Vec<2>(0.1, 0.2);
  m2.ramp_time = 0.4;
  WallMotion<3> m3;
  m3.velocity = Vec<3>(0.3, -0.1, 0.2);
  m3.angular_velocity = Vec<3>(0.5, -1.0, 2.0);
  m3.axis_point = Vec<3>(0.1, 0.2, -0.3);
  m3.ramp_time = 0.4;
  const Vec<2> x02(0.7, -0.4);
  const Vec<3> x03(0.7, -0.4, 0.25);
  for (double t : {0.0, 0.13, 0.31, 0.4, 0.9}) {
    const double e = 1e-6;
    CAPTURE(t);
    Vec<2> x, u, a, xp, up, ap, xm, um, am;
    MovingWalls<2>::kinematics(m2, t, x02, x, u, a);
    MovingWalls<2>::kinematics(m2, t + e, x02, xp, up, ap);
    MovingWalls<2>::kinematics(m2, t - e, x02, xm, um, am);
    if (t > 0) {  // centred differences (one-sided at t = 0, where the ramp starts)
      CHECK(((xp - xm) / (2 * e) - u).norm() < 1e-7);
      // (the acceleration has a kink at the ramp's end, t = T: f'' jumps)
      if (t != m2.ramp_time) CHECK(((up - um) / (2 * e) - a).norm() < 2e-6);
    }
    // rigid: the distance to the (moving) axis point is kept
    CHECK((x - (m2.axis_point + m2.clock(t) * m2.velocity)).norm() == doctest::Approx((x02 - m2.axis_point).norm()).epsilon(1e-13));
    Vec<3> y, v, b, yp, vp, bp, ym, vm, bm;
    MovingWalls<3>::kinematics(m3, t, x03, y, v, b);
    MovingWalls<3>::kinematics(m3, t + e, x03, yp, vp, bp);
    MovingWalls<3>::kinematics(m3, t - e, x03, ym, vm, bm);
    if (t > 0) {
      CHECK(((yp - ym) / (2 * e) - v).norm() < 1e-7);
      if (t != m3.ramp_time) CHECK(((vp - vm) / (2 * e) - b).norm() < 2e-6);
    }
    // the component along the axis of x - c(t) is kept
    const Vec<3> axis = m3.angular_velocity.normalized();
    CHECK((y - (m3.axis_point + m3.clock(t) * m3.velocity)).dot(axis) == doctest::Approx((x03 - m3.axis_point).dot(axis)));
  }
  // 3D rotation about z reproduces 2D
  WallMotion<3> z;
  z.angular_velocity = Vec<3>(0, 0, 2.5);
  z.axis_point = Vec<3>(0.1, 0.2, 0.0);
  WallMotion<2> z2;
  z2.angular_velocity = z.angular_velocity;
  z2.axis_point = Vec<2>(0.1, 0.2);
  Vec<3> y, v, b;
  Vec<2> x, u, a;
  MovingWalls<3>::kinematics(z, 0.7, Vec<3>(0.7, -0.4, 0.3), y, v, b);
  MovingWalls<2>::kinematics(z2, 0.7, Vec<2>(0.7, -0.4), x, u, a);
  CHECK(std::abs(y[0] - x[0]) < 1e-14);
  CHECK(std::abs(y[1] - x[1]) < 1e-14);
  CHECK(y[2] == 0.3);
  CHECK(std::abs(v[0] - u[0]) < 1e-14);
  CHECK(std::abs(b[1] - a[1]) < 1e-13);
  // the ramp: at rest at t = 0, full speed after T, clock continuous
  CHECK(m2.factor(0.0) == 0.0);
  CHECK(m2.factor(0.4) == 1.0);
  CHECK(m2.clock(0.4) == doctest::Approx(0.2));
  CHECK(m2.clock(1.0) == doctest::Approx(0.8));
}

TEST_CASE("moving walls: the walls are placed from t at every evaluation, not integrated") {
  SceneHeader h;
  Config cfg = loadScene(kBox, {}, h);
  auto sim = build<2>(cfg, h);
  SphSystem<2>& sys = sim->system();
  ParticleSet<2>& P = sys.particles;
  const std::size_t n = P.n_moving;
  std::vector<double> x0(P.position.begin() + 2 * n, P.position.end());
  std::vector<double> y = sim->state(), ydot(y.size());
  const double omega = 4.0;
  auto check_at = [&](double t) {
    sys.evaluate(t, y.data(), ydot.data());
    const double c = std::cos(omega * t), s = std::sin(omega * t);
    double err_x = 0, err_v = 0;
    for (std::size_t k = 0; k < P.nFixed(); ++k) {
      const double px = x0[2 * k], py = x0[2 * k + 1];
      const double ex = c * px - s * py, ey = s * px + c * py;
      err_x = std::max(err_x, std::hypot(P.position[2 * (n + k)] - ex, P.position[2 * (n + k) + 1] - ey));
      err_v = std::max(err_v, std::hypot(P.velocity[2 * (n + k)] + omega * ey, P.velocity[2 * (n + k) + 1] - omega * ex));
    }
    CHECK(err_x < 1e-18);
    CHECK(err_v < 1e-15);
  };
  check_at(0.05);
  check_at(0.3);
  check_at(0.0);  // back in time: the same positions as at the start
  for (std::size_t k = 0; k < x0.size(); ++k) CHECK(P.position[2 * n + k] == x0[k]);
}

TEST_CASE("moving walls: a fluid in solid-body rotation with its walls is a steady state of the no-slip mirror") {
  // The dummy layers mirror the fluid's velocity relative to the rigid motion: with the fluid
  // in solid-body rotation omega x x, every wall particle's ghost velocity is omega x x_w (the
  // rigid field at the particle), so the viscous force vanishes.
  SceneHeader h;
  Config cfg = loadScene(kBox, {}, h);
  auto sim = build<2>(cfg, h);
  SphSystem<2>& sys = sim->system();
  ParticleSet<2>& P = sys.particles;
  const std::size_t n = P.n_moving;
  std::vector<double> y = sim->state(), ydot(y.size());
  const double omega = 4.0, t = 0.1;
  const double c = std::cos(omega * t), s = std::sin(omega * t);
  for (std::size_t i = 0; i < n; ++i) {  // the fluid turned with the box and rotating with it
    const double px = y[2 * i], py = y[2 * i + 1];
    y[2 * i] = c * px - s * py;
    y[2 * i + 1] = s * px + c * py;
    y[3 * n + 2 * i] = -omega * y[2 * i + 1];
    y[3 * n + 2 * i + 1] = omega * y[2 * i];
  }
  sys.evaluate(t, y.data(), ydot.data());
  const Field* ghost = P.fields.find("wall_velocity");
  REQUIRE(ghost != nullptr);
  double err = 0;
  for (std::size_t w = n; w < P.size(); ++w) {
    const double gx = ghost->data[2 * (w - n)], gy = ghost->data[2 * (w - n) + 1];
    err = std::max(err, std::hypot(gx + omega * P.position[2 * w + 1], gy - omega * P.position[2 * w]));
  }
  CHECK(err < 1e-14);  // wall speeds ~ 3e-3 m/s
  // The viscous force (the implicit part of the split, whatever the integrator) nearly vanishes
  // on every fluid particle: the lattice continues into the walls, so the sums of the linear
  // field cancel, up to the walls' densities in the viscous weights, which vary by about 5e-4
  // (the centrifugal wall pressure, rho0 |a_w| r). Below 1e-4 of the scale of one viscous term,
  // nu (omega L/2) / dx^2 = 3.2 m/s^2. (With the plain mirror 2 u_w - v~, without the rigid
  // motion's average, the spun-up box settled 3.7 % off solid-body rotation: validation.md §15.)
  sys.rhsPart(RhsPart::implicit_part, t, y.data(), ydot.data());
  double amax = 0;
  for (std::size_t i = 0; i < n; ++i) amax = std::max(amax, std::hypot(ydot[3 * n + 2 * i], ydot[3 * n + 2 * i + 1]));
  CHECK(amax < 1e-4 * 1e-6 * omega * 5e-4 / (2.5e-5 * 2.5e-5));
}

TEST_CASE("moving walls: a translating wall's ghost velocity is 2 U - the fluid's average") {
  SceneHeader h;
  Config cfg = loadScene(kCouette, {}, h);
  auto sim = build<2>(cfg, h);
  SphSystem<2>& sys = sim->system();
  ParticleSet<2>& P = sys.particles;
  const std::size_t n = P.n_moving;
  std::vector<double> y = sim->state(), ydot(y.size());
  const double U = 1e-3, t = 0.07;
  const std::vector<double> x_start(P.position.begin() + 2 * n, P.position.end());
  for (std::size_t i = 0; i < n; ++i) y[3 * n + 2 * i] = 0.25 * U;  // a uniform fluid velocity
  sys.evaluate(t, y.data(), ydot.data());
  const Field* ghost = P.fields.find("wall_velocity");
  REQUIRE(ghost != nullptr);
  for (std::size_t w = n; w < P.size(); ++w) {
    const bool upper = P.position[2 * w + 1] > 1e-3;
    CHECK(P.velocity[2 * w] == (upper ? U : 0.0));
    if (P.kind[w] != static_cast<std::uint8_t>(ParticleKind::wall)) continue;  // no fluid neighbour
    CHECK(ghost->data[2 * (w - n)] == doctest::Approx(upper ? 1.75 * U : -0.25 * U).epsilon(1e-12));
  }
  // the upper wall moved by U t along x (periodic: wrapped into the domain), the lower one not
  for (std::size_t w = n; w < P.size(); ++w) {
    const bool upper = P.position[2 * w + 1] > 1e-3;
    const double x0 = x_start[2 * (w - n)];
    CHECK(P.position[2 * w] == sys.domain.wrap(0, upper ? x0 + U * t : x0));
  }
}

TEST_CASE("moving walls: under arkode-imex the wall velocity is in b(x), J w does not see it") {
  // f_I(y) = L(x) v + b(x): the difference f_I(y + w) - f_I(y) (ARKODE's J w) of the Couette
  // scene with its moving wall equals that of the same scene with the wall at rest.
  auto jw = [](bool moving, std::vector<double>& fI) {
    SceneHeader h;
    std::vector<std::string> over = {"integrator.type=\"arkode-imex\""};
    if (!moving) over.push_back("blocks[2].velocity=[0.0, 0.0]");
    Config cfg = loadScene(kCouette, over, h);
    Simulation<2> sim(cfg, h);
    SphSystem<2>& sys = sim.system();
    const std::size_t n = sys.particles.n_moving;
    std::vector<double> y = sim.state(), w(y.size(), 0.0), yw, f0(y.size()), f1(y.size());
    for (std::size_t i = 0; i < n; ++i) {
      y[3 * n + 2 * i] = 1e-4 * std::sin(3.0 * static_cast<double>(i));
      w[3 * n + 2 * i] = 2e-4 * std::cos(7.0 * static_cast<double>(i));
      w[3 * n + 2 * i + 1] = 1e-4 * std::sin(5.0 * static_cast<double>(i));
    }
    yw = y;
    for (std::size_t k = 0; k < y.size(); ++k) yw[k] += w[k];
    sys.rhsPart(RhsPart::implicit_part, 0.0, y.data(), f0.data());
    sys.rhsPart(RhsPart::implicit_part, 0.0, yw.data(), f1.data());
    fI = f0;
    std::vector<double> d(y.size());
    for (std::size_t k = 0; k < y.size(); ++k) d[k] = f1[k] - f0[k];
    return d;
  };
  std::vector<double> f_moving, f_rest;
  const std::vector<double> a = jw(true, f_moving), b = jw(false, f_rest);
  REQUIRE(a.size() == b.size());
  double scale = 0, diff = 0, offset = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::max(scale, std::abs(a[k]));
    diff = std::max(diff, std::abs(a[k] - b[k]));
    offset = std::max(offset, std::abs(f_moving[k] - f_rest[k]));
  }
  CHECK(scale > 0);
  CHECK(offset > 1e3 * diff);  // the moving wall changes f_I (its b(x)) ...
  CHECK(diff <= 1e-12 * scale);  // ... but not J w
}

TEST_CASE("moving walls: 3D, a rotation vector; the walls turned about it at t, the fluid at rest mirrored") {
  SceneHeader h;
  Config cfg = loadScene(kBox3, {}, h);
  Simulation<3> sim(cfg, h);
  SphSystem<3>& sys = sim.system();
  ParticleSet<3>& P = sys.particles;
  const std::size_t n = P.n_moving;
  const std::vector<double> x0(P.position.begin() + 3 * n, P.position.end());
  std::vector<double> y = sim.state(), ydot(y.size());
  const double omega = 4.0, t = 0.15;
  sys.evaluate(t, y.data(), ydot.data());
  const double c = std::cos(omega * t), s = std::sin(omega * t);
  double err_x = 0, err_v = 0;
  for (std::size_t k = 0; k < P.nFixed(); ++k) {
    const double px = x0[3 * k], py = x0[3 * k + 1], pz = x0[3 * k + 2];
    const double ex = c * px - s * py, ey = s * px + c * py;
    const std::size_t w = n + k;
    err_x = std::max({err_x, std::abs(P.position[3 * w] - ex), std::abs(P.position[3 * w + 1] - ey),
                      std::abs(P.position[3 * w + 2] - pz)});
    err_v = std::max({err_v, std::abs(P.velocity[3 * w] + omega * ey), std::abs(P.velocity[3 * w + 1] - omega * ex),
                      std::abs(P.velocity[3 * w + 2])});
  }
  CHECK(err_x < 1e-18);
  CHECK(err_v < 1e-15);
  // A wall particle touching the fluid at rest: its ghost velocity is u_w + omega x (x~_f - x_w)
  // with a zero z component.
  const Field* ghost = P.fields.find("wall_velocity");
  REQUIRE(ghost != nullptr);
  double gz = 0, gxy = 0;
  for (std::size_t w = n; w < P.size(); ++w) {
    gz = std::max(gz, std::abs(ghost->data[3 * (w - n) + 2]));
    gxy = std::max(gxy, std::hypot(ghost->data[3 * (w - n)], ghost->data[3 * (w - n) + 1]));
  }
  CHECK(gz < 1e-18);
  CHECK(gxy > 1e-3);  // the walls move (omega r ~ 3e-3 m/s)
}

TEST_CASE("moving walls: bad input is refused with the key, the units and the fix") {
  auto refuse = [](const char* scene, std::vector<std::string> over, const std::string& what) {
    SceneHeader h;
    try {
      Config cfg = loadScene(scene, over, h);
      Simulation<2> sim(cfg, h);
      FAIL("accepted: " << what);
    } catch (const InputError& e) {
      CHECK_MESSAGE(std::string(e.what()).find(what) != std::string::npos, e.what());
    }
  };
  refuse(kCouette, {"blocks[0].angular_velocity=1.0"}, "blocks[0].angular_velocity: expected no angular_velocity on a fluid block");
  refuse(kCouette, {"blocks[0].ramp_time=1.0"}, "blocks[0].ramp_time: expected no ramp_time on a fluid block");
  refuse(kCouette, {"blocks[2].angular_velocity=1.0"}, "blocks[2].angular_velocity: expected an axis_point with angular_velocity");
  refuse(kCouette, {"blocks[2].axis_point=[0.0, 0.0]"}, "blocks[2].axis_point: expected no axis_point without angular_velocity");
  refuse(kCouette, {"blocks[1].ramp_time=0.1"}, "blocks[1].ramp_time: expected no ramp_time on a wall at rest");
  refuse(kCouette, {"blocks[2].ramp_time=-0.1"}, "blocks[2].ramp_time: expected a non-negative number (s)");
  refuse(kBox, {"blocks[1].angular_velocity=[0.0, 0.0, 1.0]"}, "in 2D one number, the rotation about z");
  {  // 3D: a vector
    SceneHeader h;
    try {
      Config cfg = loadScene(kBox3, {"blocks[1].angular_velocity=4.0"}, h);
      Simulation<3> sim(cfg, h);
      FAIL("accepted a number as a 3D angular_velocity");
    } catch (const InputError& e) {
      CHECK_MESSAGE(std::string(e.what()).find("blocks[1].angular_velocity: expected an array of 3 numbers (rad/s; in 3D the vector omega)") !=
                        std::string::npos,
                    e.what());
    }
  }
  refuse(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian_image_walls.toml",
         {"blocks[2].angular_velocity=1.0", "blocks[2].axis_point=[0.0, 0.0]"},
         "expected no rotation with treatment = \"image\"");
}
