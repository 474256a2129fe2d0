// Constitutive rate functions alone, on homogeneous flows, against closed-form solutions:
// a tight fixed-step RK4 integration of dS/dt = rate(kappa, S) (independent of SPH).
#include <doctest/doctest.h>

#include <cmath>

#include "vesph/physics/constitutive/oldroyd_b.hpp"
#include "one_particle.hpp"

using namespace vesph;

namespace {

// Classical RK4 with n steps to time t for a constant velocity gradient.
template <class Rate>
Mat<2> integrate(const Rate& rate, const Mat<2>& kappa, double t, int n) {
  Mat<2> S = Mat<2>::Zero();
  const double h = t / n;
  for (int k = 0; k < n; ++k) {
    const Mat<2> k1 = rate.template operator()<2>(kappa, S);
    const Mat<2> k2 = rate.template operator()<2>(kappa, Mat<2>(S + 0.5 * h * k1));
    const Mat<2> k3 = rate.template operator()<2>(kappa, Mat<2>(S + 0.5 * h * k2));
    const Mat<2> k4 = rate.template operator()<2>(kappa, Mat<2>(S + h * k3));
    S += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return S;
}

}  // namespace

TEST_CASE("constitutive: Oldroyd-B start-up of simple shear matches the closed form") {
  // v_x = g y: kappa_xy = g. Closed form (Bird, Armstrong & Hassager, UCM/Oldroyd-B):
  //   S_xy = eta_p g (1 - e^{-t/lambda}),  S_xx = 2 eta_p lambda g^2 [1 - e^{-t/lambda}(1 + t/lambda)],
  //   S_yy = 0. RK4 with 4000 steps: error ~1e-13 relative, far below the 1e-9 asserted.
  const OldroydBRate rate{0.3, 2.0};
  const double g = 1.7;
  Mat<2> kappa = Mat<2>::Zero();
  kappa(0, 1) = g;
  for (double t : {0.05, 0.3, 1.0, 3.0}) {
    const Mat<2> S = integrate(rate, kappa, t, 4000);
    const double e = std::exp(-t / rate.lambda);
    const double sxy = rate.eta_p * g * (1 - e);
    const double sxx = 2 * rate.eta_p * rate.lambda * g * g * (1 - e * (1 + t / rate.lambda));
    CHECK(S(0, 1) == doctest::Approx(sxy).epsilon(1e-9));
    CHECK(S(1, 0) == doctest::Approx(sxy).epsilon(1e-9));
    CHECK(S(0, 0) == doctest::Approx(sxx).epsilon(1e-9));
    CHECK(std::abs(S(1, 1)) < 1e-12);
  }
  // Steady shear: first normal stress difference N1 = 2 eta_p lambda g^2, shear stress eta_p g.
  const Mat<2> S = integrate(rate, kappa, 30 * rate.lambda, 20000);
  CHECK(S(0, 0) - S(1, 1) == doctest::Approx(2 * rate.eta_p * rate.lambda * g * g).epsilon(1e-9));
  CHECK(S(0, 1) == doctest::Approx(rate.eta_p * g).epsilon(1e-9));
}

TEST_CASE("constitutive: Oldroyd-B planar extension reaches the closed-form steady stresses") {
  // kappa = diag(e, -e), 2 lambda e < 1: steady S_xx = 2 eta_p e/(1 - 2 lambda e),
  // S_yy = -2 eta_p e/(1 + 2 lambda e); the transient is exponential, so at t = 60 lambda/(1-2 lambda e)
  // it has decayed below 1e-12.
  const OldroydBRate rate{0.5, 1.5};
  const double e = 0.6;  // 2 lambda e = 0.6
  Mat<2> kappa = Mat<2>::Zero();
  kappa(0, 0) = e;
  kappa(1, 1) = -e;
  const double t = 60 * rate.lambda / (1 - 2 * rate.lambda * e);
  const Mat<2> S = integrate(rate, kappa, t, 40000);
  CHECK(S(0, 0) == doctest::Approx(2 * rate.eta_p * e / (1 - 2 * rate.lambda * e)).epsilon(1e-9));
  CHECK(S(1, 1) == doctest::Approx(-2 * rate.eta_p * e / (1 + 2 * rate.lambda * e)).epsilon(1e-9));
  CHECK(std::abs(S(0, 1)) < 1e-12);
  // Past the coil-stretch limit 2 lambda e > 1 the Oldroyd-B stress grows without bound.
  kappa(0, 0) = 1.5;
  kappa(1, 1) = -1.5;
  const Mat<2> grow = integrate(rate, kappa, 10.0, 20000);
  CHECK(grow(0, 0) > 1e3 * rate.eta_p);
}

TEST_CASE("constitutive: symmetric tensor packing round-trips in 2D and 3D") {
  Mat<2> a;
  a << 1, 2, 2, 3;
  double s2[3];
  packSymmetric<2>(a, s2);
  CHECK(s2[0] == 1);
  CHECK(s2[1] == 2);
  CHECK(s2[2] == 3);
  CHECK(unpackSymmetric<2>(s2) == a);
  Mat<3> b;
  b << 1, 2, 3, 2, 4, 5, 3, 5, 6;
  double s3[6];
  packSymmetric<3>(b, s3);
  CHECK(unpackSymmetric<3>(s3) == b);
  CHECK(s3[0] == 1);
  CHECK(s3[3] == 4);
  CHECK(s3[5] == 6);
}

TEST_CASE("constitutive 3D: the Oldroyd-B effect's six components in shear in every coordinate plane and in uniaxial extension") {
  // The 3D effect as the solver runs it (registry, velocity_gradient field, 6-component state
  // xx, xy, xz, yy, yz, zz), integrated by RK4 against the closed forms of the upper-convected
  // Maxwell stress (Bird, Armstrong & Hassager):
  //   shear v_a = g x_b (kappa_ab = g, a != b): S_ab = eta_p g (1 - e^{-t/lambda}),
  //     S_aa = 2 eta_p lambda g^2 [1 - e^{-t/lambda}(1 + t/lambda)], every other component 0;
  //   uniaxial extension along a (kappa = diag with e on a, -e/2 on the other two), 2 lambda e < 1:
  //     steady S_aa = 2 eta_p e/(1 - 2 lambda e), the other diagonal components -eta_p e/(1 + lambda e).
  // A packing that mixed up the component order, or a rate that dropped a 3D term of
  // kappa S + S kappa^T, fails one of the planes or axes.
  const double lambda = 0.5, eta = 2e-3;
  test_support::OneParticle<3> ob("[effects.oldroyd_b]\nrelaxation_time = 0.5\npolymer_viscosity = 2e-3\n");
  REQUIRE(ob.evolving.size() == 1);
  REQUIRE(ob.evolving[0]->components == 6);
  auto index = [](int a, int b) {
    static const int table[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    return table[a][b];
  };
  auto integrate3 = [&](const Mat<3>& kappa, double t, int n) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(6);
    const double h = t / n;
    for (int k = 0; k < n; ++k) {
      const Eigen::VectorXd k1 = ob.rates(kappa, y);
      const Eigen::VectorXd k2 = ob.rates(kappa, y + 0.5 * h * k1);
      const Eigen::VectorXd k3 = ob.rates(kappa, y + 0.5 * h * k2);
      const Eigen::VectorXd k4 = ob.rates(kappa, y + h * k3);
      y += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return y;
  };
  const double g = 1.7;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      if (a == b) continue;
      CAPTURE(a);
      CAPTURE(b);
      Mat<3> kappa = Mat<3>::Zero();
      kappa(a, b) = g;
      for (double t : {0.3, 1.0, 3.0}) {
        const Eigen::VectorXd y = integrate3(kappa, t, 3000);
        const double e = std::exp(-t / lambda);
        const double sab = eta * g * (1 - e), saa = 2 * eta * lambda * g * g * (1 - e * (1 + t / lambda));
        CHECK(y[index(a, b)] == doctest::Approx(sab).epsilon(1e-9));
        CHECK(y[index(a, a)] == doctest::Approx(saa).epsilon(1e-9));
        for (int c = 0; c < 6; ++c)
          if (c != index(a, b) && c != index(a, a)) CHECK(std::abs(y[c]) < 1e-12 * saa);
      }
    }
  const double rate = 0.6;  // 2 lambda e = 0.6 < 1
  for (int a = 0; a < 3; ++a) {
    CAPTURE(a);
    Mat<3> kappa = Mat<3>::Identity() * (-0.5 * rate);
    kappa(a, a) = rate;
    const Eigen::VectorXd y = integrate3(kappa, 60 * lambda / (1 - 2 * lambda * rate), 30000);
    for (int c = 0; c < 3; ++c) {
      const double expect = c == a ? 2 * eta * rate / (1 - 2 * lambda * rate) : -eta * rate / (1 + lambda * rate);
      CHECK(y[index(c, c)] == doctest::Approx(expect).epsilon(1e-9));
    }
    for (int c : {index(0, 1), index(0, 2), index(1, 2)}) CHECK(std::abs(y[c]) < 1e-14 * eta);
  }
}
