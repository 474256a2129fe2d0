// The stabilisers: artificial viscosity (Fang et al. 2006 eqs. 30-37,
// src/physics/artificial_viscosity.cpp), XSPH (thesis §3.6, src/physics/xsph.cpp) and the
// artificial stress (Fang eqs. 38-44, include/vesph/physics/artificial_stress.hpp,
// src/physics/artificial_stress.cpp), plus the Effect::prepare hook of the pair driver.
//
// Each effect is run inside a real SphSystem (the solver's right-hand side) built by hand from
// a few particles or a lattice, with only [effects.equation_of_state] beside it (which sets the
// pressure and sound speed but adds no force), so dv/dt and dx/dt - v are the effect's alone.
// Reference values are computed here from Kernel::W / Kernel::dWdr and the printed equations.
#include <doctest/doctest.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "vesph/physics/artificial_stress.hpp"
#include "vesph/physics/registry.hpp"
#include "vesph/sim/simulation.hpp"
#include "vesph/sim/system.hpp"
#include "vesph/time/integrator.hpp"
#include "vesph/time/integrator_factory.hpp"

#include "hand_built_system.hpp"

using namespace vesph;
using vesph::testing::Box;
using vesph::testing::kRho0;
using vesph::testing::kSound;

namespace {

// Jitters a periodic lattice and gives it random velocities, densities and masses (before
// Box::finish, which builds the neighbour list).
template <int D>
void disorder(Box<D>& b, std::mt19937_64& rng, double dv, double drho) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<D>& p = b.sys.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < D; ++a) {
      p.position[D * i + a] = b.sys.domain.wrap(a, p.position[D * i + a] + 0.3 * b.dx * u(rng));
      p.velocity[D * i + a] = dv * u(rng);
    }
    p.density[i] = kRho0 * (1 + drho * u(rng));
    p.mass[i] *= 1 + 0.1 * u(rng);
  }
}

template <int D>
Vec<D> unit(int a) {
  Vec<D> e = Vec<D>::Zero();
  e[a] = 1.0;
  return e;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Artificial viscosity

TEST_CASE("artificial viscosity: one pair, approaching and separating, against eqs. (31)-(35)") {
  const double dx = 0.01, alpha = 0.7, beta = 1.9;
  for (double r_over_dx : {0.4, 1.0, 1.7}) {
    for (double sign : {-1.0, 1.0}) {  // -1: approaching
      CAPTURE(r_over_dx);
      CAPTURE(sign);
      Box<2> b("[effects.artificial_viscosity]\nalpha = 0.7\nbeta = 1.9\n", dx, 1.5, KernelType::cubic, 1.0, false);
      const double r = r_over_dx * dx, u = 0.3, rho1 = 1003.0, rho2 = 996.0;
      // particle 1 at the origin moving along +x (towards particle 2 when sign = -1 ...)
      b.add(Vec<2>(0.0, 0.0), Vec<2>(-sign * u, 0.1), rho1, b.mass());
      b.add(Vec<2>(r, 0.0), Vec<2>(sign * u, 0.1), rho2, 1.3 * b.mass());
      b.finish();
      b.evaluate();
      if (sign > 0) {  // separating: v12 . x12 = (-2u)(-r) > 0 -> Pi = 0, eq. (32)
        CHECK(b.dvdt(0).norm() == 0.0);
        CHECK(b.dvdt(1).norm() == 0.0);
        continue;
      }
      // by hand: x12 = (-r, 0), v12 = (2u, 0)
      const double h = b.sys.kernel.h, vx = 2 * u * (-r);
      const double phi = h * vx / (r * r + 0.01 * h * h);
      const double Pi = (-alpha * kSound * phi + beta * phi * phi) / (0.5 * (rho1 + rho2));
      const double F = b.sys.kernel.dWdr(r) / r;
      const double expect1 = -1.3 * b.mass() * Pi * F * (-r);  // dv_1x = -m_2 Pi F x12
      CHECK(Pi > 0);
      CHECK(b.dvdt(0)[0] == doctest::Approx(expect1).epsilon(1e-12));
      CHECK(b.dvdt(0)[0] < 0);  // pushed away from particle 2 (which is at +x)
      CHECK(b.dvdt(0)[1] == 0.0);
      CHECK(b.mass() * b.dvdt(0)[0] + 1.3 * b.mass() * b.dvdt(1)[0] == doctest::Approx(0.0).scale(std::abs(expect1) * b.mass()));
    }
  }
}

TEST_CASE("artificial viscosity: zero for a uniform velocity and for an expanding block") {
  const double dx = 0.01;
  {
    Box<2> b("[effects.artificial_viscosity]\nalpha = 1.0\nbeta = 2.0\n", dx, 1.6, KernelType::quintic, 24 * dx, true);
    b.lattice(24, [](const Vec<2>&) { return Vec<2>(0.4, -0.25); });
    std::mt19937_64 rng(3);
    disorder(b, rng, 0.0, 0.03);
    for (std::size_t i = 0; i < b.sys.particles.size(); ++i) b.sys.particles.v(i) = Vec<2>(0.4, -0.25);
    b.finish();
    b.evaluate();
    double worst = 0;
    for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, b.dvdt(i).norm());
    CHECK(worst == 0.0);
  }
  {  // v = gamma x: every pair separates (v_ij . x_ij = gamma r^2 > 0)
    Box<2> b("[effects.artificial_viscosity]\nalpha = 1.0\nbeta = 2.0\n", dx, 1.6, KernelType::quintic, 1.0, false);
    b.lattice(20, [](const Vec<2>& x) { return Vec<2>(2.0 * x); });
    b.finish();
    b.evaluate();
    double worst = 0;
    for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, b.dvdt(i).norm());
    CHECK(worst == 0.0);
    // and a converging block (v = -gamma x, every pair approaching with the same Pi(r)) is
    // decelerated: inside, the pair forces cancel by symmetry; the particles within 3 dx of
    // the block's edge are all pushed outwards.
    for (std::size_t i = 0; i < b.sys.particles.size(); ++i) b.sys.particles.v(i) *= -1.0;
    b.evaluate();
    int outward = 0, total = 0;
    const Vec<2> centre = Vec<2>::Constant(10 * dx);
    for (std::size_t i = 0; i < b.n(); ++i) {
      const Vec<2> rel = Vec<2>(b.sys.particles.x(i)) - centre;
      if (rel.cwiseAbs().maxCoeff() < 7 * dx) continue;
      ++total;
      outward += b.dvdt(i).dot(rel) > 0;
    }
    CHECK(total == 400 - 14 * 14);
    CHECK(outward == total);
  }
}

namespace {

// Disordered periodic set with random velocities: sum_i m_i dv_i/dt = 0 to rounding, and the
// kinetic energy decreases, dE/dt = sum_i m_i v_i . dv_i/dt = -sum_pairs m_i m_j Pi_ij F_ij v_ij . x_ij < 0.
template <int D>
void avConservation(Box<D>& b, std::mt19937_64& rng) {
  disorder(b, rng, 0.5, 0.05);
  b.finish();
  b.evaluate();
  const ParticleSet<D>& p = b.sys.particles;
  Vec<D> P = Vec<D>::Zero();
  double P_abs = 0, dE = 0, dE_abs = 0;
  for (std::size_t i = 0; i < b.n(); ++i) {
    P += p.mass[i] * b.dvdt(i);
    P_abs += p.mass[i] * b.dvdt(i).norm();
    dE += p.mass[i] * p.v(i).dot(b.dvdt(i));
    dE_abs += p.mass[i] * std::abs(p.v(i).dot(b.dvdt(i)));
  }
  MESSAGE(D, "D: |sum m dv/dt| / sum m |dv/dt| = ", P.norm() / P_abs, ", dE/dt / sum |m v.dv/dt| = ", dE / dE_abs);
  CHECK(P_abs > 0);
  CHECK(P.norm() < 1e-13 * P_abs);
  CHECK(dE < 0);
}

}  // namespace

TEST_CASE("artificial viscosity: conserves momentum and dissipates kinetic energy on a disordered periodic set") {
  std::mt19937_64 rng(11);
  {
    Box<2> b("[effects.artificial_viscosity]\nalpha = 1.0\nbeta = 2.0\n", 0.01, 1.5, KernelType::quintic, 24 * 0.01, true);
    b.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
    avConservation(b, rng);
  }
  {
    Box<3> b("[effects.artificial_viscosity]\nalpha = 0.5\nbeta = 0\n", 0.01, 1.3, KernelType::wendland_c2, 10 * 0.01, true);
    b.lattice(10, [](const Vec<3>&) { return Vec<3>::Zero(); });
    avConservation(b, rng);
  }
}

TEST_CASE("artificial viscosity: needs a sound speed; keys are checked") {
  Config cfg = Config::fromString("[effects.artificial_viscosity]\nalpha = 1\n", "test");
  ConfigTable root = cfg.root();
  ConfigTable eff = root.table("effects");
  SphSystem<2> sys;
  sys.kernel = Kernel(KernelType::quintic, 2, 0.016);
  sys.domain.hi = Vec<2>::Constant(1.0);
  sys.particles.add(Vec<2>::Constant(0.5), Vec<2>::Zero(), kRho0, 0.1, ParticleKind::fluid, 0);
  sys.particles.n_moving = 1;
  sys.effects = makeEffects<2>(eff);
  CHECK_THROWS_WITH_AS(sys.setup(0.01, kRho0, 0.0, 0.001), doctest::Contains("add [effects.equation_of_state]"), InputError);
  Config bad = Config::fromString("[effects.artificial_viscosity]\nbeta = -1\n", "test");
  ConfigTable broot = bad.root();
  ConfigTable beff = broot.table("effects");
  CHECK_THROWS_WITH_AS(makeEffects<2>(beff), doctest::Contains("non-negative"), InputError);
}

// ---------------------------------------------------------------------------------------------
// XSPH

TEST_CASE("xsph: a uniform velocity is unchanged; one moving particle drifts towards its neighbours") {
  const double dx = 0.01, eps = 0.5;
  for (const std::string form : {"monaghan", "normalised"}) {
    CAPTURE(form);
    const std::string keys = "[effects.xsph]\nform = \"" + form + "\"\n";
    {
      Box<2> b(keys, dx, 1.6, KernelType::quintic, 20 * dx, true);
      b.lattice(20, [](const Vec<2>&) { return Vec<2>(0.3, -0.2); });
      std::mt19937_64 rng(5);
      disorder(b, rng, 0.0, 0.05);
      for (std::size_t i = 0; i < b.sys.particles.size(); ++i) b.sys.particles.v(i) = Vec<2>(0.3, -0.2);
      b.finish();
      b.evaluate();
      double worst = 0;
      for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, (b.dxdt(i) - Vec<2>(0.3, -0.2)).norm());
      CHECK(worst == 0.0);
    }
    // Regular periodic lattice at rest but for particle k moving with u: by hand,
    //   monaghan:   dx_k/dt = u (1 - eps V S),  dx_j/dt = eps V W(|x_j - x_k|) u   (V = m/rho = dx^2)
    //   normalised: dx_k/dt = u (1 - eps S/(W(0) + S)),  dx_j/dt = eps W_jk u / (W(0) + S)
    // with S = sum over lattice offsets d != 0 of W(|d|), from Kernel::W.
    Box<2> b(keys, dx, 1.6, KernelType::quintic, 20 * dx, true);
    b.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
    const std::size_t k = 10 * 20 + 10;
    const Vec<2> u(0.2, 0.05);
    b.sys.particles.v(k) = u;
    b.finish();
    b.evaluate();
    const Kernel& K = b.sys.kernel;
    double S = 0;
    for (int i = -6; i <= 6; ++i)
      for (int j = -6; j <= 6; ++j)
        if (i || j) S += K.W(dx * std::hypot(i, j));
    const double V = dx * dx, W0 = K.W(0.0);
    const bool norm = form == "normalised";
    const Vec<2> expect_k = norm ? Vec<2>(u * (1 - eps * S / (W0 + S))) : Vec<2>(u * (1 - eps * V * S));
    MESSAGE(form, ": dx_k/dt = ", b.dxdt(k).transpose(), " (v = ", u.transpose(), "), V S = ", V * S);
    CHECK((b.dxdt(k) - expect_k).norm() < 1e-12 * u.norm());
    CHECK(b.dxdt(k).norm() < u.norm());  // pulled towards the neighbours' mean (zero)
    const std::size_t j = k + 1;          // the neighbour at +dx
    const Vec<2> expect_j = norm ? Vec<2>(eps * K.W(dx) / (W0 + S) * u) : Vec<2>(eps * V * K.W(dx) * u);
    CHECK((b.dxdt(j) - expect_j).norm() < 1e-12 * u.norm());
    CHECK(b.dvdt(k).norm() == 0.0);  // positions only
  }
}

TEST_CASE("xsph: the monaghan form conserves momentum, sum m_i (dx_i/dt - v_i) = 0") {
  std::mt19937_64 rng(17);
  double ratio[2];
  for (int f = 0; f < 2; ++f) {
    Box<2> b(f == 0 ? "[effects.xsph]\nepsilon = 0.8\n" : "[effects.xsph]\nepsilon = 0.8\nform = \"normalised\"\n", 0.01,
             1.5, KernelType::quintic, 24 * 0.01, true);
    b.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
    disorder(b, rng, 1.0, 0.05);  // random masses and densities too
    b.finish();
    b.evaluate();
    const ParticleSet<2>& p = b.sys.particles;
    Vec<2> P = Vec<2>::Zero();
    double P_abs = 0;
    for (std::size_t i = 0; i < b.n(); ++i) {
      const Vec<2> d = b.dxdt(i) - p.v(i);
      P += p.mass[i] * d;
      P_abs += p.mass[i] * d.norm();
    }
    CHECK(P_abs > 0);
    ratio[f] = P.norm() / P_abs;
  }
  MESSAGE("|sum m (dx/dt - v)| / sum m |dx/dt - v|: monaghan ", ratio[0], ", normalised ", ratio[1]);
  CHECK(ratio[0] < 1e-13);
  CHECK(ratio[1] > 1e-6);  // the thesis' Shepard form is not symmetric: the two forms differ
}

TEST_CASE("xsph: wall particles are not averaged in; the leapfrog moves particles with dx/dt") {
  {  // the channel with walls, the fluid moving uniformly: XSPH changes nothing
    SceneHeader h;
    Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml",
                           {"effects.xsph.epsilon=0.5", "initial.velocity=[1e-5, 0.0]"}, h);
    Simulation<2> sim(cfg, h);
    std::vector<double> y = sim.state(), ydot(y.size());
    sim.system().evaluate(0.0, y.data(), ydot.data());
    const std::size_t n = sim.system().particles.n_moving;
    double worst = 0;
    for (std::size_t k = 0; k < n * 2; ++k) worst = std::max(worst, std::abs(ydot[k] - y[n * 3 + k]));
    CHECK(y[n * 3] == 1e-5);
    CHECK(worst == 0.0);
  }
  // One leapfrog step: the position must follow dx/dt (with the XSPH part) over the whole step,
  // not only over the predictor's half (to O(dt^2)).
  const double dx = 0.01;
  Box<2> b("[effects.xsph]\n", dx, 1.6, KernelType::quintic, 20 * dx, true);
  b.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
  const std::size_t k = 10 * 20 + 10;
  b.sys.particles.v(k) = Vec<2>(0.2, 0.0);
  b.finish();
  b.evaluate();
  const std::vector<double> rate = b.ydot, y0 = b.y;
  for (const char* type : {"leapfrog", "midpoint"}) {
    CAPTURE(type);
    const double dt = 1e-6;
    Config icfg = Config::fromString(std::string("type = \"") + type + "\"\nstep = 1e-6\n", "test");
    ConfigTable t = icfg.root();
    auto integ = makeIntegrator(t, ReferenceScales{dx, kRho0, 0.01, 0.2});
    std::vector<double> y = y0;
    integ->start(b.sys, 0.0, y.data());
    REQUIRE(integ->advance(dt));
    for (std::size_t i : {k, k + 1, k + 20}) {
      const Vec<2> moved = (Eigen::Map<const Vec<2>>(y.data() + 2 * i) - Eigen::Map<const Vec<2>>(y0.data() + 2 * i)) / dt;
      const Vec<2> rate_i = Eigen::Map<const Vec<2>>(rate.data() + 2 * i);
      CHECK((moved - rate_i).norm() < 1e-4 * 0.2);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Artificial stress

TEST_CASE("artificial stress: zero under compression, -eps sigma'/rho^2 along tensile principal axes") {
  const double eps = 0.3, rho = 990.0, s = -eps / (rho * rho);
  // pure pressure p > 0 (compression) and any compressive state: R = 0
  for (double p : {1.0, 1e5})
    CHECK(artificialStress<2>(-p * Mat<2>::Identity(), rho, eps).norm() == 0.0);
  CHECK(artificialStress<3>(-7.0 * Mat<3>::Identity(), rho, eps).norm() == 0.0);
  Mat<3> comp;  // all eigenvalues negative (-10 -+ 6 sqrt 2, -10) but not diagonally dominant
  comp << -10, 6, 6, 6, -10, 0, 6, 0, -10;
  CHECK(artificialStress<3>(comp, rho, eps).norm() == 0.0);
  Mat<2> comp2;  // eigenvalues -1 and -9
  comp2 << -5, 4, 4, -5;
  CHECK(artificialStress<2>(comp2, rho, eps).norm() == 0.0);
  // negative pressure (isotropic tension): R = eps p / rho^2 I, i.e. -eps |p| / rho^2 I
  const double p = -250.0;
  CHECK((artificialStress<2>(-p * Mat<2>::Identity(), rho, eps) - s * (-p) * Mat<2>::Identity()).norm() < 1e-15 * std::abs(s * p));
  CHECK((artificialStress<3>(-p * Mat<3>::Identity(), rho, eps) - s * (-p) * Mat<3>::Identity()).norm() < 1e-15 * std::abs(s * p));
  // uniaxial tension along x with compression along y: R only along x
  Mat<2> uni;
  uni << 40.0, 0.0, 0.0, -90.0;
  const Mat<2> R = artificialStress<2>(uni, rho, eps);
  CHECK(R(0, 0) == doctest::Approx(s * 40.0).epsilon(1e-14));
  CHECK(R(0, 0) < 0);
  CHECK(std::abs(R(0, 1)) < 1e-15 * std::abs(s * 40.0));
  CHECK(std::abs(R(1, 1)) < 1e-15 * std::abs(s * 40.0));
}

TEST_CASE("artificial stress: rotation to the principal axes and back (eqs. 40-44) against a rotated diagonal state") {
  const double eps = 0.5, rho = 1010.0, s = -eps / (rho * rho);
  // 2D: sigma = Q(phi) diag(a, b) Q^T built here; R must be Q diag(R'(a), R'(b)) Q^T for every
  // angle, including the degenerate directions of Fang's eq. (41) (sigma_xx = sigma_yy at 45 deg).
  for (double a_b : {0.0, 1.0}) {
    const double a = 35.0, b = a_b == 0.0 ? -20.0 : 12.0;
    for (int k = 0; k <= 24; ++k) {
      const double phi = -M_PI + k * M_PI / 12.0 + (k % 5 == 0 ? 0.0 : 0.013);
      CAPTURE(phi);
      CAPTURE(b);
      const Mat<2> Q = Eigen::Rotation2Dd(phi).toRotationMatrix();
      const Mat<2> sigma = Q * Vec<2>(a, b).asDiagonal() * Q.transpose();
      const Vec<2> rp(s * a, b > 0 ? s * b : 0.0);
      const Mat<2> expect = Q * rp.asDiagonal() * Q.transpose();
      const Mat<2> R = artificialStress<2>(sigma, rho, eps);
      CHECK((R - expect).norm() < 1e-13 * expect.norm());
      CHECK(std::abs(R(0, 1) - R(1, 0)) == 0.0);
    }
  }
  // 3D: random rotations of diag(a, b, c) with mixed signs
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 50; ++k) {
    const Vec<3> axis = Vec<3>(u(rng), u(rng), u(rng)).normalized();
    const Mat<3> Q = Eigen::AngleAxisd(M_PI * u(rng), axis).toRotationMatrix();
    const Vec<3> lam(50 * u(rng), 50 * u(rng), 50 * u(rng));
    const Mat<3> sigma = Q * lam.asDiagonal() * Q.transpose();
    Vec<3> rp;
    for (int a = 0; a < 3; ++a) rp[a] = lam[a] > 0 ? s * lam[a] : 0.0;
    const Mat<3> expect = Q * rp.asDiagonal() * Q.transpose();
    const Mat<3> R = artificialStress<3>(sigma, rho, eps);
    CHECK((R - expect).norm() < 1e-12 * std::max(expect.norm(), std::abs(s) * 50));
  }
  // 2D planar state embedded in 3D gives the same R
  Mat<2> s2;
  s2 << 12.0, -30.0, -30.0, 4.0;
  Mat<3> s3 = Mat<3>::Zero();
  s3.topLeftCorner<2, 2>() = s2;
  s3(2, 2) = -1.0;
  CHECK((artificialStress<3>(s3, rho, eps).topLeftCorner<2, 2>() - artificialStress<2>(s2, rho, eps)).norm() <
        1e-13 * artificialStress<2>(s2, rho, eps).norm());
}

TEST_CASE("artificial stress: one pair in tension, f_ij = W(r)/W(dx) of eq. (39), zero under compression") {
  const double dx = 0.01, eps = 0.25;
  const Kernel K(KernelType::cubic, 2, 1.5 * dx);
  // Fang: for the cubic spline with h = 1.5 dx, W(0)/W(dx) = 1.8
  CHECK(K.W(0.0) / K.W(dx) == doctest::Approx(1.8).epsilon(1e-12));
  for (double r_over_dx : {1.0, 0.5, 1.6}) {
    for (double rho : {998.0, 1002.0}) {  // p = c^2 (rho - rho0): tension, compression
      CAPTURE(r_over_dx);
      CAPTURE(rho);
      Box<2> b("[effects.artificial_stress]\nepsilon = 0.25\n", dx, 1.5, KernelType::cubic, 1.0, false);
      const double r = r_over_dx * dx;
      b.add(Vec<2>(0.0, 0.0), Vec<2>::Zero(), rho, b.mass());
      b.add(Vec<2>(0.0, r), Vec<2>::Zero(), rho, b.mass());
      b.finish();
      b.evaluate();
      const double p = kSound * kSound * (rho - kRho0);
      if (p > 0) {
        CHECK(b.dvdt(0).norm() == 0.0);
        CHECK(b.dvdt(1).norm() == 0.0);
        continue;
      }
      const double R = -eps * (-p) / (rho * rho);  // sigma = -p I > 0: R = -eps sigma/rho^2 I
      const double f = K.W(r) / K.W(dx);
      if (r_over_dx == 1.0) CHECK(f == doctest::Approx(1.0).epsilon(1e-14));
      const double expect = b.mass() * std::pow(f, 4) * (K.dWdr(r) / r) * 2 * R * (-r);  // y component, x_12 = (0, -r)
      CHECK(b.dvdt(0)[1] == doctest::Approx(expect).epsilon(1e-12));
      CHECK(b.dvdt(0)[1] < 0);  // repulsive: particle 0 pushed away from particle 1 (above it)
      CHECK(b.dvdt(0)[0] == 0.0);
      CHECK(b.dvdt(1)[1] == doctest::Approx(-expect).epsilon(1e-12));
    }
  }
}

namespace {

// Disordered periodic set, p = c^2 (rho - rho0) of both signs, a random elastic stress S (a
// field no effect evolves, set by hand): the field artificial_stress holds R(-p I + S) for
// every particle, and sum_i m_i dv_i/dt = 0 to rounding.
template <int D>
void asConservation(Box<D>& b, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  disorder(b, rng, 0.1, 0.002);  // p in [-200, 200] Pa
  Field& S = b.sys.particles.fields.require("elastic_stress", symmetricComponents<D>());
  b.finish();
  for (double& s : S.data) s = 150.0 * u(rng);
  b.evaluate();
  const ParticleSet<D>& p = b.sys.particles;
  const Field* R = p.fields.find("artificial_stress");
  REQUIRE(R);
  const Field* pres = p.fields.find("pressure");
  int tensile = 0, zero = 0, wrong = 0;
  for (std::size_t i = 0; i < b.n(); ++i) {
    const Mat<D> sigma = -pres->data[i] * Mat<D>::Identity() + unpackSymmetric<D>(S.at(i));
    const Mat<D> expect = artificialStress<D>(sigma, p.density[i], 0.4);
    wrong += (unpackSymmetric<D>(R->at(i)) - expect).norm() > 1e-15 * (1 + expect.norm());
    const Eigen::SelfAdjointEigenSolver<Mat<D>> es(sigma);
    const bool tension = es.eigenvalues().maxCoeff() > 0;
    (tension ? tensile : zero) += 1;
    if (!tension) CHECK(expect.norm() == 0.0);
    if (tension) CHECK(expect.norm() > 0.0);
  }
  CHECK(wrong == 0);
  CHECK(tensile > 50);
  CHECK(zero > 10);
  Vec<D> P = Vec<D>::Zero();
  double P_abs = 0;
  for (std::size_t i = 0; i < b.n(); ++i) {
    P += p.mass[i] * b.dvdt(i);
    P_abs += p.mass[i] * b.dvdt(i).norm();
  }
  MESSAGE(D, "D artificial stress: ", tensile, " particles in tension, ", zero, " not; |sum m dv/dt| / sum m |dv/dt| = ",
          P.norm() / P_abs);
  CHECK(P_abs > 0);
  CHECK(P.norm() < 1e-13 * P_abs);
}

}  // namespace

TEST_CASE("artificial stress: momentum conservation and R = R(-p I + S) on a disordered set with an elastic stress") {
  std::mt19937_64 rng(23);
  {
    Box<2> b("[effects.artificial_stress]\nepsilon = 0.4\nexponent = 3\n", 0.01, 1.5, KernelType::quintic, 24 * 0.01, true);
    b.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
    asConservation(b, rng);
  }
  {
    Box<3> b("[effects.artificial_stress]\nepsilon = 0.4\nexponent = 3\n", 0.01, 1.3, KernelType::wendland_c2, 10 * 0.01, true);
    b.lattice(10, [](const Vec<3>&) { return Vec<3>::Zero(); });
    asConservation(b, rng);
  }
}

TEST_CASE("artificial stress: wall particles carry R from their own pressure; bad keys are refused") {
  SceneHeader h;
  // p0 < 0 puts the whole channel in tension.
  Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml",
                         {"effects.artificial_stress.epsilon=0.3", "effects.equation_of_state.reference_pressure=-1e-4"}, h);
  Simulation<2> sim(cfg, h);
  std::vector<double> y = sim.state(), ydot(y.size());
  SphSystem<2>& sys = sim.system();
  sys.evaluate(0.0, y.data(), ydot.data());
  const ParticleSet<2>& p = sys.particles;
  const Field* R = p.fields.find("artificial_stress");
  const Field* pres = p.fields.find("pressure");
  REQUIRE(R);
  REQUIRE(R->range == Field::Range::all);
  int nonzero = 0;
  for (std::size_t w = p.n_moving; w < p.size(); ++w) {
    const Mat<2> expect = artificialStress<2>(-pres->data[w] * Mat<2>::Identity(), p.density[w], 0.3);
    CHECK((unpackSymmetric<2>(R->at(w)) - expect).norm() <= 1e-15 * (1 + expect.norm()));
    nonzero += expect.norm() > 0;
  }
  CHECK(nonzero == static_cast<int>(p.nFixed()));

  auto refuses = [](const std::string& set, const std::string& needle) {
    SceneHeader hh;
    try {
      Config c = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml", {set}, hh);
      Simulation<2> s(c, hh);
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(needle) != std::string::npos);
      return;
    }
    FAIL("no InputError for " << set);
  };
  refuses("effects.artificial_stress.epsilon=1.5", "effects.artificial_stress.epsilon");
  refuses("effects.artificial_stress.exponent=0", "effects.artificial_stress.exponent");
  refuses("effects.artificial_stress.exponent=2.5", "effects.artificial_stress.exponent");
}

// ---------------------------------------------------------------------------------------------
// The prepare hook

namespace {

// A pair effect that records which particles prepare() visited and whether every pair term saw
// its neighbour's prepared value.
template <int D>
class Probe final : public PairEffect<D, Probe<D>> {
 public:
  explicit Probe(bool prepares) : prepares_(prepares) {}
  std::string_view name() const override { return "probe"; }
  Phase phase() const override { return Phase::forces; }
  bool prepares() const override { return prepares_; }
  void setup(Setup<D>& s) override { value_ = &s.particles.fields.require("probe", 1); }
  void prepare(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    for (std::size_t k = begin; k < end; ++k) {
      calls[k] += 1;
      value_->data[k] = 2.0 * k + 1.0;
    }
  }
  struct Local {
    bool ok;
  };
  Local begin(const RhsContext<D>&, Index) const { return {true}; }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    l.ok = l.ok && value_->data[nb.j] == 2.0 * nb.j + 1.0;
  }
  void end(const RhsContext<D>&, Index i, Local& l) const { seen[i] = l.ok ? 1 : 2; }

  mutable std::vector<int> calls, seen;

 private:
  bool prepares_;
  Field* value_ = nullptr;
};

}  // namespace

TEST_CASE("pair driver: prepare() covers every particle, moving and fixed, once per pass, before the pair terms") {
  for (bool prepares : {true, false}) {
    CAPTURE(prepares);
    // 72 x 72 lattice (5184 particles, above the parallel threshold), the outer 4 layers fixed.
    const double dx = 0.01;
    Box<2> b("", dx, 1.3, KernelType::wendland_c2, 1.0, false);
    const int n = 72, frame = 4;
    for (int pass = 0; pass < 2; ++pass)
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const bool fixed = i < frame || j < frame || i >= n - frame || j >= n - frame;
          if (fixed != (pass == 1)) continue;
          b.add(Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), kRho0, b.mass(), fixed);
        }
    auto probe = std::make_unique<Probe<2>>(prepares);
    Probe<2>* pr = probe.get();
    pr->calls.assign(b.sys.particles.size(), 0);
    pr->seen.assign(b.sys.particles.n_moving, 0);
    std::vector<std::unique_ptr<Effect<2>>> extra;
    extra.push_back(std::move(probe));
    b.finish(std::move(extra));
    b.evaluate();
    int once = 0, ok = 0;
    for (int c : pr->calls) once += c == 1;
    for (int s : pr->seen) ok += s == 1;
    if (prepares) {
      CHECK(once == static_cast<int>(b.sys.particles.size()));
      CHECK(ok == static_cast<int>(b.n()));
    } else {
      CHECK(once == 0);
      CHECK(ok == 0);  // never prepared: the neighbours' values are not there
    }
    b.evaluate();
    int twice = 0;
    for (int c : pr->calls) twice += c == 2;
    CHECK(twice == (prepares ? static_cast<int>(b.sys.particles.size()) : 0));
  }
}

// ---------------------------------------------------------------------------------------------
// Density diffusion (delta-SPH, Molteni & Colagrossi 2009; src/physics/density_diffusion.cpp):
//   d rho_i/dt += delta h c sum_j 2 (rho_j - rho_i + rho0 g . r_ij / c^2) (-F_ij) m_j/rho_j

namespace {

template <int D>
double drhodt(const Box<D>& b, std::size_t i) {
  return b.ydot[b.n() * D + i];
}

// Density rho(x) on every particle with the masses rho_i dx^2: uniform volumes, so that the
// pair sums are linear in the density field.
template <class Fn>
void setDensityField(Box<2>& b, double dx, Fn&& rho) {
  for (std::size_t i = 0; i < b.sys.particles.size(); ++i) {
    b.sys.particles.density[i] = rho(Vec<2>(b.sys.particles.x(i)));
    b.sys.particles.mass[i] = b.sys.particles.density[i] * dx * dx;
  }
}

}  // namespace

TEST_CASE("density diffusion: one pair against the formula; zero for a uniform density; a bump is smoothed") {
  const double dx = 0.01, delta = 0.13;
  {  // one pair, by hand
    Box<2> b("[effects.density_diffusion]\ndelta = 0.13\n", dx, 1.5, KernelType::cubic, 1.0, false);
    const double r = 0.8 * dx, rho1 = 1010.0, rho2 = 990.0, m1 = b.mass(), m2 = 1.3 * b.mass();
    b.add(Vec<2>(0.0, 0.0), Vec<2>(0.1, 0.0), rho1, m1);
    b.add(Vec<2>(0.6 * r, 0.8 * r), Vec<2>(0.0, -0.2), rho2, m2);
    b.finish();
    b.evaluate();
    const double h = b.sys.kernel.h, F = b.sys.kernel.dWdr(r) / r;
    const double expect1 = delta * h * kSound * 2 * (rho2 - rho1) * (-F) * m2 / rho2;
    const double expect2 = delta * h * kSound * 2 * (rho1 - rho2) * (-F) * m1 / rho1;
    CHECK(expect1 < 0);  // the denser particle loses density
    CHECK(drhodt(b, 0) == doctest::Approx(expect1).epsilon(1e-12));
    CHECK(drhodt(b, 1) == doctest::Approx(expect2).epsilon(1e-12));
    // sum_i (m_i/rho_i) d rho_i/dt = 0
    CHECK(m1 / rho1 * drhodt(b, 0) + m2 / rho2 * drhodt(b, 1) == doctest::Approx(0.0).scale(std::abs(m1 / rho1 * expect1)));
    CHECK(b.dvdt(0).norm() == 0.0);  // density only
    CHECK((b.dxdt(0) - Vec<2>(0.1, 0.0)).norm() == 0.0);
  }
  // A disordered periodic set of uniform density (random positions and masses): exactly zero.
  Box<2> b("[effects.density_diffusion]\n", dx, 1.5, KernelType::cubic, 20 * dx, true);
  b.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
  std::mt19937_64 rng(23);
  disorder(b, rng, 0.3, 0.0);
  b.finish();
  b.evaluate();
  double worst = 0;
  for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, std::abs(drhodt(b, i)));
  CHECK(worst == 0.0);
  // A density bump on one particle k of a regular lattice: d rho_k/dt < 0, its neighbours gain,
  // d rho_j/dt = 2 delta h c (rho_k - rho0)(-F(|x_k - x_j|)) V_k for a neighbour j.
  Box<2> c("[effects.density_diffusion]\n", dx, 1.5, KernelType::cubic, 20 * dx, true);
  c.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
  const std::size_t k = 10 * 20 + 10;
  c.sys.particles.density[k] = 1.02 * kRho0;
  c.finish();
  c.evaluate();
  CHECK(drhodt(c, k) < 0);
  const double h = c.sys.kernel.h, coeff = 0.1 * h * kSound;
  for (std::size_t j : {k + 1, k + 21}) {
    const double r = (Vec<2>(c.sys.particles.x(j)) - Vec<2>(c.sys.particles.x(k))).norm();
    const double expect = coeff * 2 * 0.02 * kRho0 * (-c.sys.kernel.dWdr(r) / r) * c.mass() / (1.02 * kRho0);
    CHECK(drhodt(c, j) > 0);
    CHECK(drhodt(c, j) == doctest::Approx(expect).epsilon(1e-12));
  }
  double total = 0;  // equal masses: sum_i d rho_i/dt / rho_i = 0
  for (std::size_t i = 0; i < c.n(); ++i) total += drhodt(c, i) / c.sys.particles.density[i];
  CHECK(std::abs(total) < 1e-13 * std::abs(drhodt(c, k)) / kRho0);
}

namespace {

// Disordered periodic set with random densities and masses: sum_i V_i d rho_i/dt = 0 to rounding
// (V_i = m_i/rho_i; the pair weights are symmetric, the differences antisymmetric) and the
// density variance decays: sum_i V_i rho_i d rho_i/dt = -delta h c sum_pairs 2 (-F) V_i V_j (rho_j - rho_i)^2 < 0.
template <int D>
void ddConservation(Box<D>& b, std::mt19937_64& rng) {
  disorder(b, rng, 0.5, 0.05);
  b.finish();
  b.evaluate();
  const ParticleSet<D>& p = b.sys.particles;
  double sum = 0, sum_abs = 0, variance_rate = 0;
  for (std::size_t i = 0; i < b.n(); ++i) {
    const double V = p.mass[i] / p.density[i];
    sum += V * drhodt(b, i);
    sum_abs += V * std::abs(drhodt(b, i));
    variance_rate += V * (p.density[i] - kRho0) * drhodt(b, i);
  }
  MESSAGE(D, "D: |sum V drho/dt| / sum V |drho/dt| = ", std::abs(sum) / sum_abs);
  CHECK(sum_abs > 0);
  CHECK(std::abs(sum) < 1e-13 * sum_abs);
  CHECK(variance_rate < 0);
}

}  // namespace

TEST_CASE("density diffusion: conserves sum_i m_i/rho_i drho_i/dt = 0 and smooths a random density field") {
  std::mt19937_64 rng(29);
  {
    Box<2> b("[effects.density_diffusion]\n", 0.01, 1.5, KernelType::cubic, 24 * 0.01, true);
    b.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
    ddConservation(b, rng);
  }
  {
    Box<3> b("[effects.density_diffusion]\ndelta = 0.2\n", 0.01, 1.3, KernelType::wendland_c2, 10 * 0.01, true);
    b.lattice(10, [](const Vec<3>&) { return Vec<3>::Zero(); });
    ddConservation(b, rng);
  }
}

TEST_CASE("density diffusion: linear field zero in the interior, hydrostatic field zero everywhere, quadratic field ~ delta h c lap(rho)") {
  const double dx = 0.01, g = 9.81;
  const int n = 20;
  const double margin = 2.0 * 1.5 * dx;  // cubic support 2h, h = 1.5 dx
  auto interior = [&](const Vec<2>& x) {
    return x.minCoeff() > margin && x.maxCoeff() < n * dx - margin;
  };
  // The hydrostatic density of gravity -g e_y with c = kSound: rho = rho0 (1 - g y / c^2).
  auto hydrostatic = [&](const Vec<2>& x) { return kRho0 * (1.0 - g * x[1] / (kSound * kSound)); };
  for (bool correction : {false, true}) {
    CAPTURE(correction);
    Box<2> b(std::string("[effects.density_diffusion]\nhydrostatic = ") + (correction ? "true" : "false") +
                 "\n[effects.body_force]\nacceleration = [0.0, -9.81]\n",
             dx, 1.5, KernelType::cubic, 1.0, false);
    b.lattice(n, [](const Vec<2>&) { return Vec<2>::Zero(); });
    setDensityField(b, dx, hydrostatic);
    b.finish();
    b.evaluate();
    // scale: the rate at the top row without the correction, ~ delta h c |grad rho| / h
    const double scale = 0.1 * kSound * kRho0 * g / (kSound * kSound);
    double worst_interior = 0, worst = 0;
    int top_positive = 0, top = 0;
    for (std::size_t i = 0; i < b.n(); ++i) {
      const Vec<2> x = b.sys.particles.x(i);
      const double rate = drhodt(b, i);
      worst = std::max(worst, std::abs(rate));
      if (interior(x)) worst_interior = std::max(worst_interior, std::abs(rate));
      if (x[1] > (n - 1) * dx) {  // the top row, the lightest particles, neighbours only below
        ++top;
        top_positive += rate > 0;
      }
    }
    MESSAGE("hydrostatic correction ", correction, ": max |drho/dt| interior ", worst_interior, ", everywhere ", worst,
            " (scale ", scale, ")");
    CHECK(worst_interior < 1e-10 * scale);  // a linear field: the lattice sum cancels in a full support
    if (correction) {
      CHECK(worst < 1e-10 * scale);  // rho - rho^H = 0 in every pair
    } else {
      CHECK(worst > 0.1 * scale);      // the truncated support at the edges does not cancel
      CHECK(top_positive == top);      // Antuono et al. 2012: the surface density is pushed away
    }
  }
  // A quadratic field rho = rho0 (1 + a |x - x_c|^2): lap rho = 4 rho0 a in 2D; the term is
  // delta h c lap(rho) in the interior to the accuracy of the SPH Laplacian on the lattice.
  // The masses m_i = rho_i dx^2 keep the volumes uniform, so that on the symmetric lattice the
  // linear part cancels and Brookshaw's sum is 4 rho0 a times the lattice moment
  // sum_j dx^2 (-F_ij) |r_ij|^2 / 2, which is 1 in the continuum (2 int W dV = 2).
  Box<2> q("[effects.density_diffusion]\n", dx, 1.5, KernelType::cubic, 1.0, false);
  q.lattice(n, [](const Vec<2>&) { return Vec<2>::Zero(); });
  const double a = 5.0;  // 1/m^2: rho varies by a (0.1 m)^2 = 5 %
  const Vec<2> centre = Vec<2>::Constant(0.5 * n * dx);
  setDensityField(q, dx, [&](const Vec<2>& x) { return kRho0 * (1.0 + a * (x - centre).squaredNorm()); });
  q.finish();
  q.evaluate();
  const double expect = 0.1 * q.sys.kernel.h * kSound * 4.0 * kRho0 * a;
  double worst_rel = 0;
  for (std::size_t i = 0; i < q.n(); ++i)
    if (interior(q.sys.particles.x(i))) worst_rel = std::max(worst_rel, std::abs(drhodt(q, i) / expect - 1.0));
  MESSAGE("quadratic field: max relative deviation from delta h c lap(rho) in the interior ", worst_rel);
  CHECK(worst_rel < 0.02);
}

// The "antuono" form (Antuono et al. 2010): the pair term -[2 (rho_j - rho_i) + (g_i + g_j) . r_ij] F_ij V_j
// with the renormalised density gradients g, computed in the gradients pass.
TEST_CASE("density diffusion, form antuono: zero for linear densities on truncated supports and for quadratic ones in the bulk; conservative; damps a bump") {
  const double dx = 0.01;
  const int n = 20;
  const double support = 2.0 * 1.5 * dx;  // cubic, h = 1.5 dx
  auto inside = [&](const Vec<2>& x, double margin) { return x.minCoeff() > margin && x.maxCoeff() < n * dx - margin; };
  // A linear density (not hydrostatic: no body force) on the open lattice, edges and corners
  // included: Molteni's sum does not vanish where the support is truncated, Antuono's does.
  const Vec<2> slope(300.0, -500.0);  // kg/m^4: 3 % and 5 % of rho0 across 0.1 m
  auto linear = [&](const Vec<2>& x) { return kRho0 + slope.dot(x); };
  double molteni_edge = 0;
  for (const std::string form : {"molteni", "antuono"}) {
    CAPTURE(form);
    Box<2> b("[effects.density_diffusion]\nform = \"" + form + "\"\n", dx, 1.5, KernelType::cubic, 1.0, false);
    b.lattice(n, [](const Vec<2>&) { return Vec<2>::Zero(); });
    setDensityField(b, dx, linear);
    b.finish();
    b.evaluate();
    double worst = 0;
    for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, std::abs(drhodt(b, i)));
    const double scale = 0.1 * kSound * slope.norm();  // ~ delta h c |grad rho| / h
    MESSAGE(form, ": linear density, max |drho/dt| over the open lattice ", worst, " (scale ", scale, ")");
    if (form == "molteni") {
      molteni_edge = worst;
      CHECK(worst > 0.1 * scale);
    } else {
      CHECK(worst < 1e-9 * scale);
      const Field* g = b.sys.particles.fields.find("density_gradient");
      REQUIRE(g != nullptr);
      double gradient_error = 0;  // the renormalised gradient is exact for a linear field
      for (std::size_t i = 0; i < b.n(); ++i)
        gradient_error = std::max(gradient_error, (Eigen::Map<const Vec<2>>(g->data.data() + 2 * i) - slope).norm());
      CHECK(gradient_error < 1e-9 * slope.norm());
    }
  }
  CHECK(molteni_edge > 0);
  // A quadratic density: Molteni's term is delta h c lap(rho) in the bulk (the test above),
  // Antuono's is zero wherever i and its neighbours have full, symmetric supports.
  const double a = 5.0;
  const Vec<2> centre = Vec<2>::Constant(0.5 * n * dx);
  Box<2> q("[effects.density_diffusion]\nform = \"antuono\"\n", dx, 1.5, KernelType::cubic, 1.0, false);
  q.lattice(n, [](const Vec<2>&) { return Vec<2>::Zero(); });
  setDensityField(q, dx, [&](const Vec<2>& x) { return kRho0 * (1.0 + a * (x - centre).squaredNorm()); });
  q.finish();
  q.evaluate();
  const double molteni_bulk = 0.1 * q.sys.kernel.h * kSound * 4.0 * kRho0 * a;
  double worst_bulk = 0, worst_edge = 0;
  for (std::size_t i = 0; i < q.n(); ++i) {
    const double rate = std::abs(drhodt(q, i));
    if (inside(q.sys.particles.x(i), 2.0 * support)) worst_bulk = std::max(worst_bulk, rate);
    else worst_edge = std::max(worst_edge, rate);
  }
  MESSAGE("antuono, quadratic density: max |drho/dt| in the bulk ", worst_bulk, ", at the edges ", worst_edge,
          " (Molteni's bulk value ", molteni_bulk, ")");
  CHECK(worst_bulk < 1e-8 * molteni_bulk);
  CHECK(worst_edge > 0);  // the edges' gradients are not exact for a quadratic: the term acts there
  // A disordered periodic set with random densities and masses: sum_i V_i d rho_i/dt = 0.
  std::mt19937_64 rng(31);
  for (int dim : {2, 3}) {
    CAPTURE(dim);
    auto check = [&](auto& b) {
      disorder(b, rng, 0.5, 0.05);
      b.finish();
      b.evaluate();
      const auto& p = b.sys.particles;
      double sum = 0, sum_abs = 0;
      for (std::size_t i = 0; i < b.n(); ++i) {
        const double V = p.mass[i] / p.density[i];
        sum += V * drhodt(b, i);
        sum_abs += V * std::abs(drhodt(b, i));
      }
      CHECK(sum_abs > 0);
      CHECK(std::abs(sum) < 1e-13 * sum_abs);
    };
    if (dim == 2) {
      Box<2> b("[effects.density_diffusion]\nform = \"antuono\"\n", 0.01, 1.5, KernelType::cubic, 24 * 0.01, true);
      b.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
      check(b);
    } else {
      Box<3> b("[effects.density_diffusion]\nform = \"antuono\"\ndelta = 0.2\n", 0.01, 1.3, KernelType::wendland_c2, 10 * 0.01, true);
      b.lattice(10, [](const Vec<3>&) { return Vec<3>::Zero(); });
      check(b);
    }
  }
  // A density bump on one particle of a periodic lattice (the particle-scale noise the term is
  // for): it still loses density, by less than under Molteni's term (the neighbours'
  // gradients see part of the bump), and the neighbours gain.
  double rates[2];
  for (int k = 0; k < 2; ++k) {
    Box<2> c(k ? "[effects.density_diffusion]\nform = \"antuono\"\n" : "[effects.density_diffusion]\n", dx, 1.5,
             KernelType::cubic, 20 * dx, true);
    c.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
    const std::size_t bump = 10 * 20 + 10;
    c.sys.particles.density[bump] = 1.02 * kRho0;
    c.finish();
    c.evaluate();
    rates[k] = drhodt(c, bump);
    CHECK(drhodt(c, bump + 1) > 0);
  }
  MESSAGE("bump: d rho/dt Molteni ", rates[0], ", Antuono ", rates[1]);
  CHECK(rates[1] < 0);
  CHECK(rates[1] > rates[0]);
}

TEST_CASE("density diffusion: wall neighbours skipped by default, included on request; needs a sound speed; keys checked") {
  const double dx = 0.01;
  for (const std::string walls : {"", "walls = \"skip\"\n", "walls = \"include\"\n"}) {
    CAPTURE(walls);
    Box<2> b("[effects.density_diffusion]\n" + walls, dx, 1.5, KernelType::cubic, 1.0, false);
    const double r = 1.1 * dx, rho_w = 1030.0;
    b.add(Vec<2>(0.0, 0.0), Vec<2>::Zero(), kRho0, b.mass());
    b.add(Vec<2>(0.0, -r), Vec<2>::Zero(), rho_w, b.mass(), true);
    b.finish();
    b.evaluate();
    if (walls.find("include") == std::string::npos) {
      CHECK(drhodt(b, 0) == 0.0);
    } else {
      const double F = b.sys.kernel.dWdr(r) / r;
      const double expect = 0.1 * b.sys.kernel.h * kSound * 2 * (rho_w - kRho0) * (-F) * b.mass() / rho_w;
      CHECK(expect > 0);
      CHECK(drhodt(b, 0) == doctest::Approx(expect).epsilon(1e-12));
    }
  }
  {  // without an equation of state there is no sound speed
    Config cfg = Config::fromString("[effects.density_diffusion]\n", "test");
    ConfigTable root = cfg.root();
    ConfigTable eff = root.table("effects");
    SphSystem<2> sys;
    sys.kernel = Kernel(KernelType::cubic, 2, 0.015);
    sys.domain.hi = Vec<2>::Constant(1.0);
    sys.particles.add(Vec<2>::Constant(0.5), Vec<2>::Zero(), kRho0, 0.1, ParticleKind::fluid, 0);
    sys.particles.n_moving = 1;
    sys.effects = makeEffects<2>(eff);
    CHECK_THROWS_WITH_AS(sys.setup(0.01, kRho0, 0.0, 0.001), doctest::Contains("add [effects.equation_of_state]"), InputError);
  }
  for (const std::string bad : {"delta = -0.1\n", "walls = \"mirror\"\n", "hydrostatic = 1\n", "form = \"fourtakas\"\n"}) {
    CAPTURE(bad);
    Config cfg = Config::fromString("[effects.density_diffusion]\n" + bad, "test");
    ConfigTable root = cfg.root();
    ConfigTable eff = root.table("effects");
    CHECK_THROWS_AS(makeEffects<2>(eff), InputError);
  }
}

TEST_CASE("image walls (Fang et al. 2006 eqs. 46-48): boundary and image values for linear fields") {
  // The Oldroyd-B channel with Fang's boundary + image particles on both walls (the fluid one
  // spacing off the surfaces, Fang Fig. 1), a linear shear v_x = gamma y, a linear pressure
  // and a stress with a constant and a linear part set in the fluid; one right-hand side.
  const double dx = 2.5e-5, H = 1e-3, gamma = 10.0;
  for (const char* mode : {"fang", "centroid"}) {
    CAPTURE(mode);
    SceneHeader h;
    const std::string ex = std::string("\"") + mode + "\"";
    Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/startup_channel_oldroyd_b.toml",
                           {"blocks[0].min=[0.0, 1.25e-5]", "blocks[0].max=[5.0e-4, 0.9875e-3]",
                            "blocks[1].treatment=\"image\"", "blocks[1].normal=[0.0, 1.0]",
                            "blocks[1].extrapolation=" + ex, "blocks[2].treatment=\"image\"",
                            "blocks[2].normal=[0.0, -1.0]", "blocks[2].extrapolation=" + ex},
                           h);
    Simulation<2> sim(cfg, h);
    SphSystem<2>& sys = sim.system();
    ParticleSet<2>& P = sys.particles;
    const std::size_t n = P.n_moving;
    // Rows: fluid at dx .. H - dx (39), walls at 0, -dx, ..., -5 dx and H, ..., H + 5 dx.
    CHECK(n == 20 * 39);
    CHECK(P.size() - n == 2 * 20 * 6);
    std::vector<double> y = sim.state(), ydot(y.size());
    Field* S = P.fields.find("elastic_stress");
    REQUIRE(S != nullptr);
    for (std::size_t i = 0; i < n; ++i) {
      const double yi = P.position[2 * i + 1];
      y[3 * n + 2 * i] = gamma * yi;  // v_x
      y[3 * n + 2 * i + 1] = 0.0;
    }
    // The stress is part of the state after the velocities: S_xx = 2 + y/H, S_xy = 1, S_yy = 3 (Pa).
    const std::size_t s0 = 5 * n;
    REQUIRE(y.size() >= s0 + 3 * n);
    for (std::size_t i = 0; i < n; ++i) {
      const double yi = P.position[2 * i + 1];
      y[s0 + 3 * i] = 2.0 + yi / H;
      y[s0 + 3 * i + 1] = 1.0;
      y[s0 + 3 * i + 2] = 3.0;
    }
    sys.evaluate(0.0, y.data(), ydot.data());
    const Field* wv = P.fields.find("wall_velocity");
    REQUIRE(wv != nullptr);
    double worst_boundary_v = 0, worst_image_v = 0, worst_nn = 0, worst_sxy = 0;
    for (std::size_t w = n; w < P.size(); ++w) {
      const double yw = P.position[2 * w + 1];
      const bool lower = yw < 0.5 * H;
      const double depth = lower ? -yw : yw - H;  // behind the surface
      const double vx = wv->data[2 * (w - n)];
      // v_x = gamma y vanishes on the floor only: the floor's image particles must carry its
      // continuation -gamma depth (eq. 47 through u_w = 0); the ceiling is not checked.
      if (!lower) continue;
      if (depth < 1e-12) {
        worst_boundary_v = std::max(worst_boundary_v, std::abs(vx));
        worst_nn = std::max(worst_nn, std::abs(S->data[3 * w + 2]));  // n.S.n = S_yy on the floor
        worst_sxy = std::max(worst_sxy, std::abs(S->data[3 * w + 1] - 1.0));
      } else {
        worst_image_v = std::max(worst_image_v, std::abs(vx - (-gamma * depth)) / (gamma * dx));
      }
    }
    CHECK(worst_boundary_v == 0.0);
    CHECK(worst_nn == 0.0);          // Fang: the normal stress component is zero on the wall
    CHECK(worst_sxy < 1e-12);        // the other components interpolated (constant: exact)
    if (std::string(mode) == "centroid")
      CHECK(worst_image_v < 1e-9);   // linear through the wall value: exact
    else
      CHECK(worst_image_v > 0.05);   // eq. 47 with the literal d_P: the interpolation bias
  }
}

// ---------------------------------------------------------------------------------------------
// Particle shifting (src/physics/particle_shifting.cpp): du_i = -A h U grad C_i added to dx/dt,
// the fields carried with (du . grad) phi, tangential only in the free-surface band.

TEST_CASE("particle shifting: a lattice is left alone, a displaced particle is pushed back, keys checked") {
  const double dx = 0.01, A = 2.0, U = 0.5;
  const std::string keys = "[effects.particle_shifting]\ncoefficient = 2.0\nspeed = 0.5\n";
  Box<2> b(keys, dx, 1.6, KernelType::quintic, 20 * dx, true);
  b.lattice(20, [](const Vec<2>&) { return Vec<2>::Zero(); });
  const std::size_t k = 10 * 20 + 10;
  const Vec<2> d(0.2 * dx, -0.1 * dx);
  b.finish();
  b.evaluate();
  double worst = 0;
  for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, b.dxdt(i).norm());
  CHECK(worst < 1e-12 * U);  // grad C = 0 on the regular lattice
  b.sys.particles.x(k) += d;
  b.evaluate();
  // By hand: grad C_k = sum_j V [1 + 0.2 (W/W(dx))^4] F r_kj over the lattice around the
  // displaced particle (r_kj = x_k - x_j), du_k = -A h U grad C_k.
  const Kernel& K = b.sys.kernel;
  Vec<2> gradC = Vec<2>::Zero();
  for (int i = -6; i <= 6; ++i)
    for (int j = -6; j <= 6; ++j) {
      if (!i && !j) continue;
      const Vec<2> r = d - dx * Vec<2>(i, j);
      const double q = r.norm();
      if (q >= K.supportRadius()) continue;
      gradC += dx * dx * (1 + 0.2 * std::pow(K.W(q) / K.W(dx), 4)) * K.dWdr(q) / q * r;
    }
  const Vec<2> expect = -A * K.h * U * gradC;
  MESSAGE("displaced by ", d.transpose(), ": dx_k/dt = ", b.dxdt(k).transpose(), ", by hand ", expect.transpose());
  CHECK((b.dxdt(k) - expect).norm() < 1e-10 * expect.norm());
  CHECK(b.dxdt(k).dot(d) < -0.95 * b.dxdt(k).norm() * d.norm());  // back towards its site
  CHECK(b.dvdt(k).norm() == 0.0);                                    // at rest: nothing to carry

  {  // 3-D: a periodic 16^3 lattice, one particle displaced
    Box<3> c(keys, dx, 1.6, KernelType::quintic, 16 * dx, true);
    c.lattice(16, [](const Vec<3>&) { return Vec<3>::Zero(); });
    c.finish();
    c.evaluate();
    double still = 0;
    for (std::size_t i = 0; i < c.n(); ++i) still = std::max(still, c.dxdt(i).norm());
    CHECK(still < 1e-12 * U);
    const std::size_t m = (8 * 16 + 8) * 16 + 8;
    const Vec<3> d3(0.15 * dx, -0.1 * dx, 0.05 * dx);
    c.sys.particles.x(m) += d3;
    c.evaluate();
    MESSAGE("3-D: displaced by ", d3.transpose(), ": dx/dt = ", c.dxdt(m).transpose());
    CHECK(c.dxdt(m).dot(d3) < -0.95 * c.dxdt(m).norm() * d3.norm());
  }

  Config missing = Config::fromString("[effects.particle_shifting]\ncoefficient = 2.0\n", "test");
  ConfigTable eff = missing.root().table("effects");
  CHECK_THROWS_WITH_AS(makeEffects<2>(eff), doctest::Contains("speed"), InputError);
}

TEST_CASE("particle shifting: velocity, density and stress carried by (du . grad) phi") {
  // Linear fields on a jittered lattice, checked on the interior particles (support full):
  // v = G x with G = [[0, a], [b, 0]], rho = rho0 (1 + c x), S = (s x, 0, s y). The difference
  // gradient of a linear field g.x is M_i g (M_i = -sum_j V_j F r_ij r_ij^T, computed here by
  // brute force over the particles), so the carried rates are d v/dt = G M_i du,
  // d rho/dt = rho0 c e_x . M_i du, dS/dt = (s e_x . M_i du, 0, s e_y . M_i du), to round-off.
  const double dx = 0.01, a = 3.0, bb = -2.0, c = 0.5, s = 100.0;
  Box<2> b("[effects.particle_shifting]\nspeed = 1.0\n[effects.velocity_gradient]\n[effects.oldroyd_b]\n"
           "relaxation_time = 0.1\npolymer_viscosity = 1.0\n",
           dx, 1.6, KernelType::quintic, 40 * dx, false);
  b.lattice(24, [&](const Vec<2>& x) { return Vec<2>(a * x[1], bb * x[0]); });
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ParticleSet<2>& p = b.sys.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int q = 0; q < 2; ++q) p.position[2 * i + q] += 0.15 * dx * u(rng);
    p.v(i) = Vec<2>(a * p.x(i)[1], bb * p.x(i)[0]);
    p.density[i] = kRho0 * (1 + c * p.x(i)[0]);
  }
  b.finish();
  Field* S = p.fields.find("elastic_stress");
  REQUIRE(S != nullptr);
  for (std::size_t i = 0; i < p.size(); ++i) {
    S->at(i)[0] = s * p.x(i)[0];
    S->at(i)[1] = 0.0;
    S->at(i)[2] = s * p.x(i)[1];
  }
  b.sys.pack(b.y.data());
  std::vector<double> with(b.y.size());
  b.sys.evaluate(0.0, b.y.data(), with.data());
  // The same without the shifting: the carried rates are the difference.
  Box<2> r("[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.1\npolymer_viscosity = 1.0\n",
           dx, 1.6, KernelType::quintic, 40 * dx, false);
  r.lattice(24, [](const Vec<2>&) { return Vec<2>::Zero(); });
  for (std::size_t i = 0; i < p.size(); ++i) {
    r.sys.particles.x(i) = p.x(i);
    r.sys.particles.v(i) = p.v(i);
    r.sys.particles.density[i] = p.density[i];
  }
  r.finish();
  Field* Sr = r.sys.particles.fields.find("elastic_stress");
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int q = 0; q < 3; ++q) Sr->at(i)[q] = S->at(i)[q];
  r.sys.pack(r.y.data());
  std::vector<double> without(r.y.size());
  r.sys.evaluate(0.0, r.y.data(), without.data());
  const std::size_t n = b.n();
  const double lo = 0.5 * dx + 4 * dx, hi = 23.5 * dx - 4 * dx;
  double err_v = 0, err_rho = 0, err_s = 0, scale = 0, deviation = 0;
  int interior = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec<2> x = p.x(i);
    if (x[0] < lo || x[0] > hi || x[1] < lo || x[1] > hi) continue;
    ++interior;
    const Vec<2> du0(with[2 * i] - without[2 * i], with[2 * i + 1] - without[2 * i + 1]);
    scale = std::max(scale, du0.norm());
    Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
    for (std::size_t j = 0; j < p.size(); ++j) {
      const Vec<2> rij = x - p.x(j);
      const double q = rij.norm();
      if (j == i || q >= b.sys.kernel.supportRadius()) continue;
      M -= p.mass[j] / p.density[j] * b.sys.kernel.dWdr(q) / q * rij * rij.transpose();
    }
    deviation = std::max(deviation, (M - Eigen::Matrix2d::Identity()).norm());
    const Vec<2> du = M * du0;  // what the difference gradients see
    const Vec<2> dv(with[3 * n + 2 * i] - without[3 * n + 2 * i], with[3 * n + 2 * i + 1] - without[3 * n + 2 * i + 1]);
    err_v = std::max(err_v, (dv - Vec<2>(a * du[1], bb * du[0])).norm() / (std::abs(a) * du.norm()));
    err_rho = std::max(err_rho, std::abs((with[2 * n + i] - without[2 * n + i]) - kRho0 * c * du[0]) / (kRho0 * c * du.norm()));
    const double* ds = with.data() + 5 * n + 3 * i;
    const double* ds0 = without.data() + 5 * n + 3 * i;
    err_s = std::max(err_s, std::abs((ds[0] - ds0[0]) - s * du[0]) / (s * du.norm()) +
                                std::abs(ds[1] - ds0[1]) / (s * du.norm()) +
                                std::abs((ds[2] - ds0[2]) - s * du[1]) / (s * du.norm()));
  }
  MESSAGE(interior, " interior particles, |du| up to ", scale, " m/s, |M - I| up to ", deviation,
          "; relative errors: v ", err_v, ", rho ", err_rho, ", S ", err_s);
  CHECK(interior > 150);
  CHECK(scale > 1e-4);       // the jitter gives a shift to carry the fields with
  CHECK(deviation > 1e-2);   // and M differs from I: the check sees which gradient is used
  CHECK(err_v < 1e-9);
  CHECK(err_rho < 1e-9);
  CHECK(err_s < 1e-9);
}

TEST_CASE("particle shifting: the free-surface band keeps only the tangential shift") {
  // A block at rest, 24 x 12 particles, no walls: the rows under its top and bottom have a
  // truncated support, so grad C points into the block. Without [effects.free_surface] they
  // are shifted outward; with it (the band: flagged particles and their neighbours) the
  // flat surfaces' shift, normal to them, is removed. Deep inside: no shift either way.
  const double dx = 0.01;
  double outward[2], band_normal[2], deep[2];
  for (int fs = 0; fs < 2; ++fs) {
    const std::string keys = std::string("[effects.particle_shifting]\nspeed = 1.0\n") +
                             (fs ? "[effects.free_surface]\nthreshold = 0.97\n" : "");
    Box<2> b(keys, dx, 1.6, KernelType::quintic, 40 * dx, false);
    for (int i = 0; i < 24; ++i)
      for (int j = 0; j < 12; ++j) b.add(Vec<2>((i + 0.5) * dx, (j + 0.5) * dx), Vec<2>::Zero(), kRho0, b.mass());
    b.finish();
    b.evaluate();
    outward[fs] = 1e300;
    band_normal[fs] = 0;
    deep[fs] = 0;
    for (std::size_t k = 0; k < b.n(); ++k) {
      const Vec<2> x = b.sys.particles.x(k);
      const bool middle = x[0] > 7 * dx && x[0] < 17 * dx;  // away from the sides
      if (!middle) continue;
      if (x[1] > 11 * dx) {  // the top row
        outward[fs] = std::min(outward[fs], b.dxdt(k)[1]);
        band_normal[fs] = std::max(band_normal[fs], std::abs(b.dxdt(k)[1]));
      }
      if (x[1] > 5 * dx && x[1] < 7 * dx && x[0] > 10 * dx && x[0] < 14 * dx) deep[fs] = std::max(deep[fs], b.dxdt(k).norm());
    }
  }
  MESSAGE("top row dy/dt: without the band >= ", outward[0], " m/s, with it |.| <= ", band_normal[1],
          "; deep inside |dx/dt| <= ", deep[0], " / ", deep[1]);
  CHECK(outward[0] > 1e-3);          // pushed out of the block without the band
  CHECK(band_normal[1] < 1e-12);     // flat surface: nothing tangential, the normal part removed
  CHECK(deep[0] < 1e-12);
  CHECK(deep[1] < 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Free-surface pressure of WCSPH (src/physics/surface_pressure.cpp)

namespace {
const std::string kOldroydB = "[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.1\npolymer_viscosity = 1.0\n";
// 24 x 12 particles at rest on a lattice of spacing dx, compressed by 1 %; then Box::finish.
void compressedBlock(Box<2>& b) {
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 12; ++j) b.add(Vec<2>((i + 0.5) * b.dx, (j + 0.5) * b.dx), Vec<2>::Zero(), 1.01 * kRho0, b.mass());
  b.finish();
}
}  // namespace

TEST_CASE("surface pressure: flagged particles carry p = n.T.n (thesis §4.2 sigma.n = 0), the others the equation of state") {
  // A block at rest, 24 x 12 particles, compressed by 1 % (EOS pressure c^2 * 10 kg/m^3 = 1000 Pa),
  // carrying a uniform elastic stress S of an Oldroyd-B fluid (no solvent: T = S). The top
  // and bottom rows' outward normals are -+y, the sides' -+x: there p = S_yy and S_xx, in the
  // corners n.S.n of their diagonal normal; the interior keeps 1000 Pa.
  const double dx = 0.01, Sxx = 3000.0, Sxy = -700.0, Syy = -400.0;
  for (const bool zero : {false, true}) {
    const std::string keys = std::string("[effects.free_surface]\n[effects.surface_pressure]\n") + (zero ? "value = \"zero\"\nambient_pressure = 50.0\n" : "");
    Box<2> b(kOldroydB + keys, dx, 1.6, KernelType::quintic, 40 * dx, false);
    compressedBlock(b);
    Field* S = b.sys.particles.fields.find("elastic_stress");
    REQUIRE(S);
    for (std::size_t k = 0; k < b.n(); ++k) {
      S->data[3 * k] = Sxx;
      S->data[3 * k + 1] = Sxy;
      S->data[3 * k + 2] = Syy;
    }
    b.evaluate();
    const double* p = b.sys.particles.fields.find("pressure")->data.data();
    const double* flag = b.sys.particles.fields.find("free_surface")->data.data();
    const double* normal = b.sys.particles.fields.find("surface_normal")->data.data();
    const Mat<2> T = (Mat<2>() << Sxx, Sxy, Sxy, Syy).finished();
    const double eos = kSound * kSound * 0.01 * kRho0;
    double worst_surface = 0, worst_interior = 0, worst_top = 0, worst_side = 0;
    int flagged = 0, interior = 0;
    for (std::size_t k = 0; k < b.n(); ++k) {
      const Vec<2> x = b.sys.particles.x(k), n(normal[2 * k], normal[2 * k + 1]);
      if (flag[k] > 0.5) {
        ++flagged;
        const double expect = zero ? 50.0 : n.dot(T * n);
        worst_surface = std::max(worst_surface, std::abs(p[k] - expect));
        if (x[1] > 11 * dx && x[0] > 7 * dx && x[0] < 17 * dx) worst_top = std::max(worst_top, (n - Vec<2>(0, 1)).norm());
        if (x[0] < dx && x[1] > 4 * dx && x[1] < 8 * dx) worst_side = std::max(worst_side, (n - Vec<2>(-1, 0)).norm());
      } else {
        ++interior;
        worst_interior = std::max(worst_interior, std::abs(p[k] - eos));
      }
    }
    MESSAGE(std::string(zero ? "zero" : "normal_stress"), ": ", flagged, " flagged, ", interior, " inside; |p - p_s| <= ", worst_surface,
            " Pa, |p - p_eos| <= ", worst_interior, " Pa; normals off by ", worst_top, " (top), ", worst_side, " (left side)");
    CHECK(flagged >= 2 * 24 + 2 * 10);  // the outermost ring at least
    CHECK(interior > 0);
    CHECK(worst_surface < 1e-9 * Sxx);
    CHECK(worst_interior < 1e-9 * eos);
    CHECK(worst_top < 1e-12);   // the top row's normal is +y by the lattice's symmetry
    CHECK(worst_side < 1e-12);  // the left column's -x
  }

  // The pressure gradient sees it: on the top row, eq. 3.18 (symmetric form) pushes a particle
  // out by sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) |grad W|; with p_i = 0 only the p_j term is
  // left, half the force (the flagged neighbours in the same row add nothing along y).
  const auto top_force = [&](bool with) {
    const std::string keys = std::string("[effects.free_surface]\n[effects.pressure_gradient]\n") + (with ? "[effects.surface_pressure]\nvalue = \"zero\"\n" : "");
    Box<2> b(kOldroydB + keys, dx, 1.6, KernelType::quintic, 40 * dx, false);
    compressedBlock(b);
    b.evaluate();
    return b.dvdt(12 * 11 + 11)[1];  // particle (11, 11): the top row, mid-width (x-major order: k = 12 i + j)
  };
  const double eos_force = top_force(false), surface_force = top_force(true);
  MESSAGE("top row dv_y/dt: equation of state ", eos_force, " m/s^2, surface pressure zero ", surface_force, " m/s^2");
  CHECK(eos_force > 0);                   // the compressed block pushes its top row out
  CHECK(std::abs(surface_force / eos_force - 0.5) < 1e-9);

  // Input errors: no free-surface detection; a normal stress without a constitutive model.
  for (const auto& [keys, message] :
       {std::pair{std::string("[effects.surface_pressure]\n"), std::string("add [effects.free_surface]")},
        std::pair{std::string("[effects.free_surface]\n[effects.surface_pressure]\n"), std::string("value = \"zero\"")}}) {
    Box<2> b(keys, dx, 1.6, KernelType::quintic, 40 * dx, false);
    b.lattice(6, [](const Vec<2>&) { return Vec<2>::Zero(); });
    CHECK_THROWS_WITH_AS(b.finish(), doctest::Contains(message.c_str()), InputError);
  }
  Config bad = Config::fromString("[effects.surface_pressure]\nvalue = \"half\"\n", "test");
  ConfigTable eff = bad.root().table("effects");
  CHECK_THROWS_WITH_AS(makeEffects<2>(eff), doctest::Contains("normal_stress"), InputError);
}

// ---------------------------------------------------------------------------------------------
// The effects in 3D (issue 33): the code is templated on the dimension; these check the 3D
// instances against what the 3D geometry requires.

TEST_CASE("free surface 3D: a lattice sphere's outermost particles are flagged and its interior is not (number density and Marrone)") {
  // A sphere of radius R dx cut from a cubic lattice (sites (i, j, k) dx with i^2 + j^2 + k^2 <=
  // R^2), Wendland C2. Outermost: a site with an empty face neighbour (the lattice's staircase
  // surface, flat faces, terraces and corners alike). Deep: farther than the support plus one
  // spacing from the surface, where the support is full (n = n_ref exactly, M = identity). Each
  // method must flag every outermost particle and no deep one; a 2D normalisation, a 2D lattice
  // sum for n_ref or a 2D scan cone would flag the bulk or miss the surface.
  // The number-density test is run where its threshold 0.8 separates the two (h = 1.6 dx, R = 7:
  // the outermost particles have n/n_ref <= 0.76). It is a resolution-dependent test: at
  // h = 1.3 dx, or on larger spheres (R = 10, h = 1.6 dx), terrace particles of the staircase
  // keep up to 0.81-0.86 of the full support and are missed (2D disks at h = 1.6 dx: at most
  // 0.797); Marrone's geometric test flags them all (docs/user-guide.md, free surface).
  struct Case {
    const char* method;
    double h_over_dx;
    int R;
  };
  for (const Case c : {Case{"number_density", 1.6, 7}, Case{"marrone", 1.3, 7}, Case{"marrone", 1.6, 10}}) {
    const std::string method = c.method;
    const int R = c.R;
    CAPTURE(method);
    CAPTURE(c.h_over_dx);
    CAPTURE(R);
    const double dx = 0.01;
    auto inside = [&](int i, int j, int k) { return i * i + j * j + k * k <= R * R; };
    Box<3> b("[effects.free_surface]\nmethod = \"" + method + "\"\n", dx, c.h_over_dx, KernelType::wendland_c2, 1.0, false);
    std::vector<std::array<int, 3>> sites;
    for (int i = -R; i <= R; ++i)
      for (int j = -R; j <= R; ++j)
        for (int k = -R; k <= R; ++k)
          if (inside(i, j, k)) {
            sites.push_back({i, j, k});
            b.add(dx * Vec<3>(i, j, k), Vec<3>::Zero(), kRho0, b.mass());
          }
    b.finish();
    b.evaluate();
    const double* flag = b.sys.particles.fields.find("free_surface")->data.data();
    const double* number = b.sys.particles.fields.find("number_density")->data.data();
    const double n_ref = b.sys.kernel.latticeSum(dx);
    const double deep_radius = R - b.sys.kernel.supportRadius() / dx - 1.0;
    int outermost = 0, outermost_flagged = 0, deep = 0, deep_flagged = 0;
    double outer_max = 0, deep_min = 1e300;
    for (std::size_t p = 0; p < sites.size(); ++p) {
      const auto [i, j, k] = sites[p];
      const bool outer = !inside(i + 1, j, k) || !inside(i - 1, j, k) || !inside(i, j + 1, k) ||
                         !inside(i, j - 1, k) || !inside(i, j, k + 1) || !inside(i, j, k - 1);
      if (outer) {
        ++outermost;
        outermost_flagged += flag[p] > 0.5;
        outer_max = std::max(outer_max, number[p] / n_ref);
      } else if (std::sqrt(double(i * i + j * j + k * k)) < deep_radius) {
        ++deep;
        deep_flagged += flag[p] > 0.5;
        deep_min = std::min(deep_min, number[p] / n_ref);
      }
    }
    MESSAGE(method, ", h = ", c.h_over_dx, " dx, R = ", R, " dx: ", sites.size(), " particles, ", outermost, " outermost (",
            outermost_flagged, " flagged, largest n/n_ref ", outer_max, "), ", deep, " deep (", deep_flagged,
            " flagged, smallest n/n_ref ", deep_min, ")");
    CHECK(outermost > 300);
    CHECK(deep > 30);
    CHECK(outermost_flagged == outermost);
    CHECK(deep_flagged == 0);
    CHECK(std::abs(deep_min - 1.0) < 1e-12);  // a full 3D support sums to the 3D lattice sum
  }
}

TEST_CASE("artificial viscosity 3D: zero for a rigid translation and rotation, a converging block is decelerated") {
  // Pi_ij acts only on approaching pairs, v_ij . x_ij < 0 (eq. 32); a rigid motion
  // v = U + omega x (x - c) has v_ij . x_ij = (omega x x_ij) . x_ij = 0 for every pair, in 3D
  // only when all three components of v_ij . x_ij enter.
  const double dx = 0.01;
  const std::string keys = "[effects.artificial_viscosity]\nalpha = 1.0\nbeta = 2.0\n";
  const Vec<3> U(0.1, 0.2, -0.3), omega(3.0, -2.0, 5.0), centre = Vec<3>::Constant(6 * dx);
  Box<3> b(keys, dx, 1.3, KernelType::wendland_c2, 1.0, false);
  b.lattice(12, [&](const Vec<3>& x) { return Vec<3>(U + omega.cross(x - centre)); });
  b.finish();
  b.evaluate();
  double rigid = 0;
  for (std::size_t i = 0; i < b.n(); ++i) rigid = std::max(rigid, b.dvdt(i).norm());
  // v = -gamma (x - c), speeds of the same order: every pair approaches
  const double gamma = omega.norm();
  for (std::size_t i = 0; i < b.sys.particles.size(); ++i)
    b.sys.particles.v(i) = -gamma * (Vec<3>(b.sys.particles.x(i)) - centre);
  b.evaluate();
  double converging = 0;
  int outward = 0, edge = 0;
  for (std::size_t i = 0; i < b.n(); ++i) {
    converging = std::max(converging, b.dvdt(i).norm());
    const Vec<3> rel = Vec<3>(b.sys.particles.x(i)) - centre;
    if (rel.cwiseAbs().maxCoeff() < 5.0 * dx) continue;  // the outer layer (5.5 dx): one-sided supports
    ++edge;
    outward += b.dvdt(i).dot(rel) > 0;
  }
  MESSAGE("max |dv/dt|: rigid motion ", rigid, ", converging ", converging);
  CHECK(converging > 0);
  CHECK(rigid <= 1e-12 * converging);
  CHECK(edge == 12 * 12 * 12 - 10 * 10 * 10);
  CHECK(outward == edge);
}

TEST_CASE("xsph 3D: a uniform velocity is unchanged; one moving particle drifts by eps V sum W (3D lattice sum)") {
  const double dx = 0.01, eps = 0.5;
  const std::string keys = "[effects.xsph]\n";
  {
    Box<3> b(keys, dx, 1.6, KernelType::quintic, 16 * dx, true);
    const Vec<3> v(0.3, -0.2, 0.1);
    b.lattice(16, [&](const Vec<3>&) { return v; });
    std::mt19937_64 rng(7);
    disorder(b, rng, 0.0, 0.05);
    for (std::size_t i = 0; i < b.sys.particles.size(); ++i) b.sys.particles.v(i) = v;
    b.finish();
    b.evaluate();
    double worst = 0;
    for (std::size_t i = 0; i < b.n(); ++i) worst = std::max(worst, (b.dxdt(i) - v).norm());
    CHECK(worst == 0.0);
  }
  // Periodic lattice at rest but for particle k moving with u: dx_k/dt = u (1 - eps V S),
  // dx_j/dt = eps V W(dx) u for its face neighbour, V = dx^3, S = the 3D lattice sum of W over
  // the offsets d != 0; and V (W(0) + S) = 1 to the lattice sum's accuracy (the 3D kernel
  // normalisation, which makes XSPH a weighted average in the bulk).
  Box<3> b(keys, dx, 1.6, KernelType::quintic, 16 * dx, true);
  b.lattice(16, [](const Vec<3>&) { return Vec<3>::Zero(); });
  const std::size_t k = (8 * 16 + 8) * 16 + 8;
  const Vec<3> u(0.2, 0.05, -0.1);
  b.sys.particles.v(k) = u;
  b.finish();
  b.evaluate();
  const Kernel& K = b.sys.kernel;
  double S = 0;
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j)
      for (int l = -5; l <= 5; ++l)
        if (i || j || l) S += K.W(dx * std::sqrt(double(i * i + j * j + l * l)));
  const double V = dx * dx * dx;
  MESSAGE("3D: V (W(0) + S) = ", V * (K.W(0.0) + S), ", dx_k/dt = ", b.dxdt(k).transpose());
  CHECK(std::abs(V * (K.W(0.0) + S) - 1.0) < 0.01);
  CHECK((b.dxdt(k) - u * (1 - eps * V * S)).norm() < 1e-12 * u.norm());
  CHECK((b.dxdt(k + 1) - eps * V * K.W(dx) * u).norm() < 1e-12 * u.norm());
  CHECK(b.dvdt(k).norm() == 0.0);
}
