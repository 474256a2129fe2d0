// Constitutive rate functions alone, on homogeneous flows, against closed-form solutions:
// a tight fixed-step RK4 integration of dS/dt = rate(kappa, S) (independent of SPH).
#include <doctest/doctest.h>

#include <cmath>

#include "vesph/physics/constitutive/oldroyd_b.hpp"

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
