// The XPP model (include/vesph/physics/constitutive/xpp.hpp, src/physics/constitutive/xpp.cpp)
// on homogeneous flows, independent of SPH: the rate function integrated by a tight fixed-step
// RK4 against (a) steady states from a Newton solve of the steady equations written out by
// components here (not through the rate function), (b) closed-form limits (small Weissenberg
// number, alpha = 0, linear relaxation of the trace with lambda_0s), (c) the 2D effect, which
// carries tau_zz as a separate field, against the 3D rate function on the same planar flows.
// Also the scene keys and the failure of a state with tr(tau) <= -3G.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "vesph/physics/constitutive/oldroyd_b.hpp"
#include "vesph/physics/constitutive/xpp.hpp"
#include "vesph/physics/registry.hpp"
#include "vesph/sim/simulation.hpp"
#include "one_particle.hpp"

using namespace vesph;
using vesph::test_support::OneParticle;

namespace {

using M3 = Mat<3>;

// A parameter set typical of the XPP literature (Verbeeten et al. 2001 fit r ~ 2-5, q ~ 1-15,
// alpha ~ 0.1-0.3), with SI values of the validation case's order.
XppRate params(double alpha = 0.15, double r = 3.0, double q = 4.0) {
  XppRate p;
  p.lambda_b = 0.5;
  p.G = 1.6e-3;
  p.r = r;
  p.nu = 2.0 / q;
  p.alpha = alpha;
  return p;
}

// Classical RK4 for dS/dt = f(S) with n steps over [0, t], from S0.
template <class State, class F>
State rk4(const F& f, State S, double t, int n) {
  const double h = t / n;
  for (int k = 0; k < n; ++k) {
    const State k1 = f(S);
    const State k2 = f(State(S + 0.5 * h * k1));
    const State k3 = f(State(S + 0.5 * h * k2));
    const State k4 = f(State(S + h * k3));
    S += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return S;
}

M3 integrate(const XppRate& p, const M3& kappa, double t, int n, const M3& S0 = M3::Zero()) {
  return rk4([&](const M3& S) { return p.operator()<3>(kappa, S); }, S0, t, n);
}

// --- The steady equations written out by components, independently of XppRate ----------------
// F of the model from the four diagonal-and-xy components (tau_xz = tau_yz = 0 in planar flow).
double relaxF(const XppRate& p, double xx, double xy, double yy, double zz) {
  const double tr = xx + yy + zz;
  const double trsq = xx * xx + 2 * xy * xy + yy * yy + zz * zz;
  const double L = std::sqrt(1 + tr / (3 * p.G));
  return 2 * p.r * std::exp(p.nu * (L - 1)) * (1 - 1 / L) + (1 - p.alpha * trsq / (3 * p.G * p.G)) / (L * L);
}

using V4 = std::array<double, 4>;  // xx, xy, yy, zz

// Steady simple shear v_x = g y: the upper-convected derivative is (-2 g xy, -g yy, 0, 0).
V4 shearResidual(const XppRate& p, double g, const V4& t) {
  const auto [xx, xy, yy, zz] = t;
  const double F = relaxF(p, xx, xy, yy, zz), a = p.alpha, G = p.G, l = p.lambda_b;
  return {2 * g * xy - (a / G * (xx * xx + xy * xy) + F * xx + G * (F - 1)) / l,
          g * yy + G * g - (a / G * xy * (xx + yy) + F * xy) / l,
          -(a / G * (xy * xy + yy * yy) + F * yy + G * (F - 1)) / l,
          -(a / G * zz * zz + F * zz + G * (F - 1)) / l};
}

// Steady planar extension v = (e x, -e y, 0): tau_xy = 0; the derivative is (-2e xx, 0, 2e yy, 0).
V4 extensionResidual(const XppRate& p, double e, const V4& t) {
  const auto [xx, xy, yy, zz] = t;
  const double F = relaxF(p, xx, 0, yy, zz), a = p.alpha, G = p.G, l = p.lambda_b;
  return {2 * e * xx + 2 * G * e - (a / G * xx * xx + F * xx + G * (F - 1)) / l, xy,
          -2 * e * yy - 2 * G * e - (a / G * yy * yy + F * yy + G * (F - 1)) / l,
          -(a / G * zz * zz + F * zz + G * (F - 1)) / l};
}

double norm(const V4& a) {
  double s = 0;
  for (double v : a) s += v * v;
  return std::sqrt(s);
}

// Damped Newton's method (central-difference Jacobian; the step is halved while the residual
// is not finite or does not decrease), with continuation in the rate from rate/64 in 24
// geometric steps, starting at tau = 0.
V4 newton(const std::function<V4(double, const V4&)>& R, double rate, const XppRate& p) {
  V4 x{0, 0, 0, 0};
  for (int level = 24; level >= 0; --level) {
    const double r = rate / std::pow(2.0, level / 4.0);
    for (int it = 0; it < 100; ++it) {
      const V4 f = R(r, x);
      Eigen::Matrix4d J;
      for (int c = 0; c < 4; ++c) {
        V4 xp = x, xm = x;
        const double d = 1e-7 * p.G;
        xp[c] += d;
        xm[c] -= d;
        const V4 fp = R(r, xp), fm = R(r, xm);
        for (int k = 0; k < 4; ++k) J(k, c) = (fp[k] - fm[k]) / (2 * d);
      }
      const Eigen::Vector4d dx = J.fullPivLu().solve(-Eigen::Vector4d(f[0], f[1], f[2], f[3]));
      double step = 1.0;
      V4 xn;
      for (int half = 0; half < 40; ++half, step *= 0.5) {
        for (int k = 0; k < 4; ++k) xn[k] = x[k] + step * dx[k];
        const double nn = norm(R(r, xn));
        if (std::isfinite(nn) && nn <= norm(f)) break;
      }
      x = xn;
      if (step * dx.cwiseAbs().maxCoeff() < 1e-15 * p.G) break;
    }
  }
  const V4 f = R(rate, x);
  for (double v : f) REQUIRE(std::abs(v) * p.lambda_b < 1e-12 * p.G);
  return x;
}

double maxAbs(const V4& a) {
  double m = 0;
  for (double v : a) m = std::max(m, std::abs(v));
  return m;
}

}  // namespace

TEST_CASE("xpp: steady simple shear by RK4 matches an independent Newton solve of the steady equations") {
  // RK4 from rest to t = 40 lambda_0b (every mode has decayed: the slowest, the linear
  // lambda_0b, by e^-40) with 16000 steps (h = lambda_0b/400; the fastest relaxation rate
  // F/lambda_0b stays below 30/s here, h F/lambda_0b < 0.04): agreement to 1e-9 of the largest
  // component. Three parameter sets, Wi = lambda_0b gdot from 0.5 to 8 (shear thinning).
  for (const XppRate p : {params(0.15, 3, 4), params(0.0, 2, 2), params(0.3, 5, 10)}) {
    for (double wi : {0.5, 2.0, 8.0}) {
      const double g = wi / p.lambda_b;
      M3 kappa = M3::Zero();
      kappa(0, 1) = g;
      const M3 S = integrate(p, kappa, 40 * p.lambda_b, 16000);
      const V4 ref = newton([&](double r, const V4& t) { return shearResidual(p, r, t); }, g, p);
      const double scale = maxAbs(ref);
      INFO("alpha = " << p.alpha << ", r = " << p.r << ", Wi = " << wi);
      CHECK(std::abs(S(0, 0) - ref[0]) < 1e-9 * scale);
      CHECK(std::abs(S(0, 1) - ref[1]) < 1e-9 * scale);
      CHECK(std::abs(S(1, 0) - ref[1]) < 1e-9 * scale);
      CHECK(std::abs(S(1, 1) - ref[2]) < 1e-9 * scale);
      CHECK(std::abs(S(2, 2) - ref[3]) < 1e-9 * scale);
      CHECK(std::abs(S(0, 2)) + std::abs(S(1, 2)) < 1e-14 * scale);
      // Out-of-plane normal stress: nonzero in flow (F != 1) ...
      CHECK(std::abs(S(2, 2)) > 1e-3 * scale);
      // ... with N2 = tau_yy - tau_zz = 0 exactly when alpha = 0 (rows yy and zz coincide),
      // negative otherwise; shear thinning: tau_xy < eta_p gdot.
      if (p.alpha == 0) CHECK(std::abs(S(1, 1) - S(2, 2)) < 1e-12 * scale);
      else CHECK(S(1, 1) - S(2, 2) < 0);
      CHECK(S(0, 1) < p.G * p.lambda_b * g);
      CHECK(S(0, 0) - S(1, 1) > 0);
    }
  }
}

TEST_CASE("xpp: steady planar extension by RK4 matches an independent Newton solve") {
  // Unlike Oldroyd-B the XPP stress stays bounded past lambda_0b e = 1/2 (finite backbone
  // stretch relaxation): Wi_e = lambda_0b e = 0.3, 1 and 3, RK4 to 40 lambda_0b.
  for (const XppRate p : {params(0.15, 3, 4), params(0.0, 2, 2)}) {
    for (double wi : {0.3, 1.0, 3.0}) {
      const double e = wi / p.lambda_b;
      M3 kappa = M3::Zero();
      kappa(0, 0) = e;
      kappa(1, 1) = -e;
      const M3 S = integrate(p, kappa, 40 * p.lambda_b, 40000);
      const V4 ref = newton([&](double r, const V4& t) { return extensionResidual(p, r, t); }, e, p);
      const double scale = maxAbs(ref);
      INFO("alpha = " << p.alpha << ", Wi_e = " << wi);
      CHECK(std::abs(S(0, 0) - ref[0]) < 1e-9 * scale);
      CHECK(std::abs(S(1, 1) - ref[2]) < 1e-9 * scale);
      CHECK(std::abs(S(2, 2) - ref[3]) < 1e-9 * scale);
      CHECK(std::abs(S(0, 1)) < 1e-14 * scale);
      CHECK(std::abs(S(2, 2)) > 1e-4 * scale);
      CHECK(std::isfinite(S(0, 0)));
    }
  }
}

TEST_CASE("xpp: small Weissenberg numbers give the linear viscoelastic limits") {
  const XppRate p = params(0.15, 3, 4);
  const double eta_p = p.G * p.lambda_b;
  // Steady shear at Wi = 1e-3: eta -> eta_p, Psi1 -> 2 eta_p lambda_0b, Psi2 -> -alpha eta_p
  // lambda_0b (the Giesekus-type term; the second-order expansion of the model). The
  // corrections are O(Wi^2) = 1e-6, asserted at 1e-4.
  {
    const double g = 1e-3 / p.lambda_b;
    const V4 t = newton([&](double r, const V4& x) { return shearResidual(p, r, x); }, g, p);
    CHECK(t[1] / (eta_p * g) == doctest::Approx(1.0).epsilon(1e-4));
    CHECK((t[0] - t[2]) / (g * g) == doctest::Approx(2 * eta_p * p.lambda_b).epsilon(1e-4));
    CHECK((t[2] - t[3]) / (g * g) == doctest::Approx(-p.alpha * eta_p * p.lambda_b).epsilon(1e-3));
  }
  // Start-up of shear at Wi = 0.01 against the UCM / Oldroyd-B closed forms (the model differs
  // at relative O(Wi^2) = 1e-4): tau_xy = eta_p g (1 - e^{-t/l}), N1 = 2 eta_p l g^2
  // [1 - e^{-t/l}(1 + t/l)]; asserted to 1e-3 relative to the steady values. At Wi = 1 the
  // same comparison must fail (the model is nonlinear): tau_xy differs by more than 10 %.
  {
    const double g = 0.01 / p.lambda_b;
    M3 kappa = M3::Zero();
    kappa(0, 1) = g;
    const OldroydBRate ob{p.lambda_b, eta_p};
    for (double t : {0.1, 0.5, 1.0, 3.0}) {
      const double T = t * p.lambda_b;
      const M3 S = integrate(p, kappa, T, 4000);
      const double e = std::exp(-t);
      CHECK(std::abs(S(0, 1) - eta_p * g * (1 - e)) < 1e-3 * eta_p * g);
      CHECK(std::abs(S(0, 0) - S(1, 1) - 2 * eta_p * p.lambda_b * g * g * (1 - e * (1 + t))) <
            1e-3 * 2 * eta_p * p.lambda_b * g * g);
      // and the Oldroyd-B rate function integrated the same way
      const Mat<2> k2 = kappa.topLeftCorner<2, 2>();
      const Mat<2> Sob = rk4([&](const Mat<2>& s) { return ob.operator()<2>(k2, s); }, Mat<2>(Mat<2>::Zero()), T, 4000);
      CHECK(std::abs(S(0, 1) - Sob(0, 1)) < 1e-3 * eta_p * g);
    }
    kappa(0, 1) = 1.0 / p.lambda_b;
    const M3 S = integrate(p, kappa, 3 * p.lambda_b, 4000);
    CHECK(S(0, 1) < 0.9 * eta_p / p.lambda_b * (1 - std::exp(-3.0)));
  }
  // No flow, a small isotropic stress tau = eps G I: the deviatoric part is zero and the trace
  // relaxes with lambda_0s = lambda_0b/r (linearisation: F - 1 = (r - 1) tr(tau)/(3G)), so
  // tr tau(t) = 3 eps G e^{-t/lambda_0s} to O(eps).
  {
    const double eps = 1e-6;
    const M3 S0 = eps * p.G * M3::Identity();
    for (double t : {0.5, 1.0, 2.0}) {
      const double T = t * p.lambda_b / p.r;
      const M3 S = integrate(p, M3::Zero(), T, 4000, S0);
      CHECK(S.trace() / (3 * eps * p.G) == doctest::Approx(std::exp(-t)).epsilon(1e-4));
      CHECK(std::abs(S(0, 0) - S(2, 2)) < 1e-12 * eps * p.G);
    }
    // With r = 1 the trace relaxes with lambda_0b instead: the r-dependence is real.
    XppRate q = p;
    q.r = 1.0;
    const M3 S = integrate(q, M3::Zero(), p.lambda_b, 4000, S0);
    CHECK(S.trace() / (3 * eps * p.G) == doctest::Approx(std::exp(-1.0)).epsilon(1e-4));
  }
}


TEST_CASE("xpp: the 2D effect with tau_zz evolves planar flows as the 3D rate function does") {
  // The 2D effect stores tau as (xx, xy, yy) plus the separate field elastic_stress_zz and
  // evaluates the rate on the 3x3 tensors; the 3D effect stores all six components. On planar
  // flows (simple shear, planar extension, and a mixed flow with rotation) all three must agree
  // with the 3x3 rate function integrated directly, to round-off.
  const std::string keys =
      "[effects.xpp]\nmodulus = 1.6e-3\nbackbone_relaxation_time = 0.5\nrelaxation_ratio = 3\n"
      "arms = 4\nanisotropy = 0.15\n";
  OneParticle<2> two(keys);
  OneParticle<3> three(keys);
  REQUIRE(two.evolving.size() == 2);
  CHECK(two.evolving[0]->name == "elastic_stress");
  CHECK(two.evolving[0]->components == 3);
  CHECK(two.evolving[1]->name == "elastic_stress_zz");
  CHECK(two.evolving[1]->components == 1);
  REQUIRE(three.size() == 6);
  const XppRate p = params(0.15, 3, 4);
  for (const Mat<2> k : {Mat<2>{{0.0, 4.0}, {0.0, 0.0}}, Mat<2>{{2.0, 0.0}, {0.0, -2.0}},
                         Mat<2>{{1.1, 3.0}, {-0.7, -1.1}}}) {
    M3 k3 = M3::Zero();
    k3.topLeftCorner<2, 2>() = k;
    const double T = 2 * p.lambda_b;
    const int n = 4000;
    const M3 ref = integrate(p, k3, T, n);
    const Eigen::VectorXd y2 = rk4([&](const Eigen::VectorXd& y) { return two.rates(k, y); },
                                   Eigen::VectorXd(Eigen::VectorXd::Zero(4)), T, n);
    const Eigen::VectorXd y3 = rk4([&](const Eigen::VectorXd& y) { return three.rates(k3, y); },
                                   Eigen::VectorXd(Eigen::VectorXd::Zero(6)), T, n);
    const double scale = ref.cwiseAbs().maxCoeff();
    INFO("kappa = " << k);
    CHECK(std::abs(y2[0] - ref(0, 0)) < 1e-12 * scale);
    CHECK(std::abs(y2[1] - ref(0, 1)) < 1e-12 * scale);
    CHECK(std::abs(y2[2] - ref(1, 1)) < 1e-12 * scale);
    CHECK(std::abs(y2[3] - ref(2, 2)) < 1e-12 * scale);
    CHECK(std::abs(ref(2, 2)) > 1e-3 * scale);  // tau_zz matters
    // 3D order: xx, xy, xz, yy, yz, zz
    CHECK(std::abs(y3[0] - ref(0, 0)) < 1e-12 * scale);
    CHECK(std::abs(y3[1] - ref(0, 1)) < 1e-12 * scale);
    CHECK(std::abs(y3[3] - ref(1, 1)) < 1e-12 * scale);
    CHECK(std::abs(y3[5] - ref(2, 2)) < 1e-12 * scale);
    CHECK(std::abs(y3[2]) + std::abs(y3[4]) < 1e-14 * scale);
  }
  // Dropping tau_zz from the traces (the 2x2 rate) is measurably wrong: the reason for the field.
  M3 k3 = M3::Zero();
  k3(0, 1) = 4.0;
  const M3 ref = integrate(p, k3, 2 * p.lambda_b, 4000);
  const Mat<2> wrong = rk4([&](const Mat<2>& s) { return p.operator()<2>(Mat<2>(k3.topLeftCorner<2, 2>()), s); },
                           Mat<2>(Mat<2>::Zero()), 2 * p.lambda_b, 4000);
  CHECK(std::abs(wrong(0, 0) - ref(0, 0)) > 1e-3 * std::abs(ref(0, 0)));
  // Oldroyd-B keeps its 3 components in 2D: no out-of-plane field.
  OneParticle<2> ob("[effects.oldroyd_b]\nrelaxation_time = 0.5\npolymer_viscosity = 1e-3\n");
  REQUIRE(ob.evolving.size() == 1);
  CHECK(ob.evolving[0]->components == 3);
}

TEST_CASE("xpp: scene keys are checked, with units in the messages") {
  auto build = [](const std::string& body) { OneParticle<2> p("[effects.xpp]\n" + body); };
  const std::string rest = "backbone_relaxation_time = 0.5\narms = 4\nanisotropy = 0.1\n";
  CHECK_NOTHROW(build("modulus = 1.0\nrelaxation_ratio = 2\n" + rest));
  CHECK_NOTHROW(build("polymer_viscosity = 0.5\nstretch_relaxation_time = 0.25\n" + rest));
  CHECK_NOTHROW(build("modulus = 1.0\nrelaxation_ratio = 1\nbackbone_relaxation_time = 0.5\narms = 1\nanisotropy = 0\n"));
  auto fails = [&](const std::string& body, const std::string& needle) {
    try {
      build(body);
    } catch (const InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(needle) != std::string::npos);
      return;
    }
    FAIL("no InputError for: " << body);
  };
  fails("relaxation_ratio = 2\n" + rest, "one of the two is required");
  fails("modulus = 1.0\npolymer_viscosity = 0.5\nrelaxation_ratio = 2\n" + rest, "not both");
  fails("modulus = 1.0\n" + rest, "stretch_relaxation_time lambda_0s (s)");
  fails("modulus = 1.0\nrelaxation_ratio = 2\nstretch_relaxation_time = 0.1\n" + rest, "not both");
  fails("modulus = 1.0\nrelaxation_ratio = 0.5\n" + rest, ">= 1");
  fails("modulus = 1.0\nstretch_relaxation_time = 1.0\n" + rest, "<= backbone_relaxation_time");
  fails("modulus = 1.0\norientation_relaxation_time = 0.1\n" + rest, "stretch_relaxation_time");
  fails("modulus = -1.0\nrelaxation_ratio = 2\n" + rest, "(Pa)");
  fails("modulus = 1.0\nrelaxation_ratio = 2\nbackbone_relaxation_time = 0.5\narms = 2.5\nanisotropy = 0.1\n",
        "whole number");
  fails("modulus = 1.0\nrelaxation_ratio = 2\nbackbone_relaxation_time = 0.5\narms = 4\nanisotropy = 1.5\n",
        "[0, 1]");
  fails("modulus = 1.0\nrelaxation_ratio = 2\narms = 4\nanisotropy = 0.1\n", "backbone_relaxation_time");
}

TEST_CASE("xpp: a state with tr(tau) <= -3G is a numerical failure, also from the solver's particle pass") {
  const XppRate p = params();
  M3 S = M3::Zero();
  S(0, 0) = -3.5 * p.G;
  CHECK_THROWS_AS(p.operator()<3>(M3::Zero(), S), NumericalFailure);
  S(0, 0) = -2.9 * p.G;  // still a positive-definite conformation tensor: fine
  CHECK_NOTHROW(p.operator()<3>(M3::Zero(), S));
  // The whole system: the channel case with one particle's tau_xx set to -4G. The failure is
  // raised inside the (OpenMP) particle pass; it must come out of rhs() as NumericalFailure,
  // naming the particle, not terminate the program.
  SceneHeader h;
  Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/startup_channel_xpp.toml", {}, h);
  Simulation<2> sim(cfg, h);
  std::vector<double> y = sim.state();
  const std::size_t n = sim.system().particles.n_moving;
  REQUIRE(sim.system().evolvingFields().size() == 2);
  const double G = 8e-4 / 0.5;
  y[n * 5 + 3 * 7] = -4 * G;  // particle 7: tau_xx, the first field after x, rho, v
  std::vector<double> ydot(y.size());
  try {
    sim.system().rhs(0.0, y.data(), ydot.data());
    FAIL("no NumericalFailure");
  } catch (const NumericalFailure& e) {
    const std::string what = e.what();
    CHECK(what.find("XPP: tr(tau)") != std::string::npos);
    CHECK(what.find("particle id 7") != std::string::npos);
  }
}
