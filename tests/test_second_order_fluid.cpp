// The second-order fluid's algebra alone (vesph/physics/constitutive/second_order_fluid.hpp):
// the steady-shear stresses of the eight forms against closed forms written out here, the
// kinematic identity D(kappa)/Dt = grad(a) - kappa kappa against finite differences along a
// particle path, frame indifference in rigid rotation, and the exact product-rule derivative
// used by procedure 4 against a central difference.
#include <doctest/doctest.h>

#include <cmath>
#include <functional>

#include "vesph/physics/constitutive/second_order_fluid.hpp"

using namespace vesph;

namespace {

const ConvectedDerivative kDerivatives[] = {ConvectedDerivative::contravariant, ConvectedDerivative::covariant,
                                           ConvectedDerivative::mixed, ConvectedDerivative::jaumann};

SecondOrderFluidLaw law(SecondOrderForm f, ConvectedDerivative d) {
  SecondOrderFluidLaw l;
  l.form = f;
  l.derivative = d;
  l.mu = 10.0;
  l.alpha1 = -2e-3;
  l.alpha2 = 2e-4;
  return l;
}

template <int D>
Mat<D> randomMatrix(unsigned seed) {
  Mat<D> m;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) m(a, b) = std::sin(1.7 * (seed + 1) * (a + 1) + 0.37 * b * (seed + 3));
  return m;
}

}  // namespace

TEST_CASE("second-order fluid: steady simple shear of the eight forms matches the closed forms") {
  // v_x = g y. Closed forms derived by hand from Table 2-1 (docs/theory.md): with
  // (c1, c2) = (alpha1, alpha2) (Rivlin-Ericksen, eq. 2.2) or (alpha1/2, -(alpha1/2 + alpha2))
  // (CEF, eq. 2.3): T_xx = (c2 + x c1) g^2, T_yy = (c2 + y c1) g^2, T_xy = mu g.
  const double g = 1600.0;
  Mat<2> K = Mat<2>::Zero();
  K(0, 1) = g;
  const double xy[4][2] = {{-2, 0}, {0, 2}, {0, 0}, {-1, 1}};
  for (SecondOrderForm f : {SecondOrderForm::rivlin_ericksen, SecondOrderForm::cef}) {
    for (int k = 0; k < 4; ++k) {
      const SecondOrderFluidLaw l = law(f, kDerivatives[k]);
      const double a1 = l.alpha1, a2 = l.alpha2;
      const double c1 = f == SecondOrderForm::cef ? 0.5 * a1 : a1;
      const double c2 = f == SecondOrderForm::cef ? -(0.5 * a1 + a2) : a2;
      const Mat<2> T = l.extra<2>(K, Mat<2>::Zero());
      CAPTURE(k);
      CAPTURE(static_cast<int>(f));
      CHECK(T(0, 1) == doctest::Approx(l.mu * g).epsilon(1e-13));
      CHECK(T(1, 0) == doctest::Approx(l.mu * g).epsilon(1e-13));
      CHECK(T(0, 0) == doctest::Approx((c2 + xy[k][0] * c1) * g * g).epsilon(1e-13));
      CHECK(T(1, 1) == doctest::Approx((c2 + xy[k][1] * c1) * g * g).epsilon(1e-13));
    }
  }
  // The thesis' own statement (§4.3.2) for Rivlin-Ericksen contravariant: T_xx = (alpha2 - 2 alpha1) g^2,
  // so N1 = -2 alpha1 g^2 with T_yy = alpha2 g^2.
  const SecondOrderFluidLaw re = law(SecondOrderForm::rivlin_ericksen, ConvectedDerivative::contravariant);
  const Mat<2> T = re.extra<2>(K, Mat<2>::Zero());
  CHECK(T(0, 0) == doctest::Approx((re.alpha2 - 2 * re.alpha1) * g * g).epsilon(1e-13));
  CHECK(T(0, 0) - T(1, 1) == doctest::Approx(-2 * re.alpha1 * g * g).epsilon(1e-13));
}

TEST_CASE("second-order fluid: Jaumann is the mean of covariant and contravariant; mixed adds an antisymmetric part") {
  for (unsigned s = 0; s < 5; ++s) {
    const Mat<3> K = randomMatrix<3>(s), A = K + K.transpose();
    const auto C = [&](ConvectedDerivative d) { return law(SecondOrderForm::rivlin_ericksen, d).convective<3>(K, A); };
    CHECK((C(ConvectedDerivative::jaumann) -
           0.5 * (C(ConvectedDerivative::covariant) + C(ConvectedDerivative::contravariant)))
              .norm() < 1e-13);
    const Mat<3> mixed = C(ConvectedDerivative::mixed);
    CHECK((mixed + mixed.transpose()).norm() < 1e-13);
    CHECK(mixed.norm() > 1e-3);  // not zero for a general gradient
  }
}

TEST_CASE("second-order fluid: D(kappa)/Dt = grad(a) - kappa kappa along a particle path") {
  // A smooth unsteady velocity field v(x, t) = B(t) x + c (x.x) + d sin(x_1). Along the path
  // through x at time t, D(kappa)/Dt by a central difference in time (following the particle to
  // second order) must equal grad(a) - kappa kappa, with the acceleration a = dv/dt + kappa v
  // and its gradient by central differences in space.
  using V3 = Eigen::Vector3d;
  const auto B = [](double t) {
    Mat<3> b;
    b << 0.3 * std::cos(t), 1.1, -0.4, 0.2, -0.5 * std::sin(2 * t), 0.7, -0.6, 0.1 * t, 0.2;
    return b;
  };
  const V3 c(0.2, -0.3, 0.1), d(0.05, 0.4, -0.2);
  const auto v = [&](const V3& x, double t) -> V3 { return B(t) * x + c * x.squaredNorm() + d * std::sin(x[0]); };
  const auto kappa = [&](const V3& x, double t) -> Mat<3> {
    Mat<3> k = B(t) + 2.0 * c * x.transpose();
    k.col(0) += d * std::cos(x[0]);
    return k;
  };
  const auto accel = [&](const V3& x, double t) -> V3 {
    const double e = 1e-6;
    return (v(x, t + e) - v(x, t - e)) / (2 * e) + kappa(x, t) * v(x, t);
  };
  const V3 x0(0.3, -0.2, 0.5);
  const double t0 = 0.4, dt = 1e-4, e = 1e-5;
  // particle positions at t0 -+ dt by RK4 backwards and forwards
  const auto advance = [&](V3 x, double t, double h) {
    const V3 k1 = v(x, t), k2 = v(x + 0.5 * h * k1, t + 0.5 * h), k3 = v(x + 0.5 * h * k2, t + 0.5 * h),
             k4 = v(x + h * k3, t + h);
    return V3(x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4));
  };
  const Mat<3> dkdt = (kappa(advance(x0, t0, dt), t0 + dt) - kappa(advance(x0, t0, -dt), t0 - dt)) / (2 * dt);
  Mat<3> G;
  for (int b = 0; b < 3; ++b) {
    V3 h = V3::Zero();
    h[b] = e;
    G.col(b) = (accel(x0 + h, t0) - accel(x0 - h, t0)) / (2 * e);
  }
  const Mat<3> K = kappa(x0, t0);
  CHECK((dkdt - (G - K * K)).norm() < 1e-5 * dkdt.norm());
  // and DA/Dt is its symmetric part, doubled
  CHECK((SecondOrderFluidLaw::materialDerivative<3>(K, G) - (dkdt + dkdt.transpose())).norm() < 1e-5 * dkdt.norm());
}

TEST_CASE("second-order fluid: a rigid rotation carries no stress in the frame-indifferent forms") {
  // v = W x with W antisymmetric: A = 0, a = W W x, grad a = W W, DA/Dt = 0; every form
  // (Table 2-1 derivatives are all applied to A = 0) gives T = 0.
  Mat<3> W;
  W << 0, -0.7, 0.2, 0.7, 0, -1.3, -0.2, 1.3, 0;
  for (SecondOrderForm f : {SecondOrderForm::rivlin_ericksen, SecondOrderForm::cef})
    for (ConvectedDerivative d : kDerivatives) {
      const SecondOrderFluidLaw l = law(f, d);
      const Mat<3> DA = SecondOrderFluidLaw::materialDerivative<3>(W, W * W);
      CHECK(DA.norm() < 1e-14);
      CHECK(l.extra<3>(W, DA).norm() < 1e-14);
    }
}

TEST_CASE("second-order fluid: the product-rule derivative of the elastic stress is exact") {
  // eps(kappa, G) is a polynomial of degree two, so the central difference with any step
  // equals the derivative up to rounding.
  for (SecondOrderForm f : {SecondOrderForm::rivlin_ericksen, SecondOrderForm::cef})
    for (ConvectedDerivative d : kDerivatives) {
      const SecondOrderFluidLaw l = law(f, d);
      const Mat<2> K = 300 * randomMatrix<2>(1), dK = 2e4 * randomMatrix<2>(2), G = 1e5 * randomMatrix<2>(3),
                   dG = 3e7 * randomMatrix<2>(4);
      const auto eps = [&](double s) {
        const Mat<2> k = K + s * dK;
        return l.elastic<2>(k, SecondOrderFluidLaw::materialDerivative<2>(k, G + s * dG));
      };
      const double s = 1e-2;
      const Mat<2> fd = (eps(s) - eps(-s)) / (2 * s);
      const Mat<2> dDA = SecondOrderFluidLaw::materialDerivativeDerivative<2>(K, dK, dG);
      const Mat<2> exact = l.elasticDerivative<2>(K, dK, dDA);
      CHECK((fd - exact).norm() < 1e-9 * exact.norm());
    }
}

TEST_CASE("second-order fluid: the quasi-steady law loses its dissipation at |c1| gamma / mu = 1") {
  // docs/theory.md §5.7: linearise T(kappa) (DA/Dt = 0) about the shear kappa = g e_x e_y and take
  // a divergence-free wave v^ perp k^; the viscosity it feels is Q(theta) = v^.T'(v^ k^T).k^ with
  // T' the derivative of T along v^ k^T (T is quadratic in kappa: the central difference is
  // exact). Claimed: min over theta of Q = mu (1 - |c1| g / mu) for the contravariant,
  // covariant and Jaumann derivatives, and Q >= mu (well posed) for the mixed one, either sign of
  // alpha1. Wi = |c1| g / mu is varied through g.
  for (SecondOrderForm f : {SecondOrderForm::rivlin_ericksen, SecondOrderForm::cef})
    for (int k = 0; k < 4; ++k)
      for (double sign : {-1.0, 1.0})
        for (double wi : {0.5, 1.0, 2.0, 3.0}) {
          SecondOrderFluidLaw l = law(f, kDerivatives[k]);
          l.alpha1 = sign * 2e-3;
          l.alpha2 = -0.1 * l.alpha1;
          const double g = wi * l.mu / std::abs(l.c1());
          Mat<2> K = Mat<2>::Zero();
          K(0, 1) = g;
          double qmin = 1e300;
          for (int n = 0; n < 720; ++n) {
            const double th = M_PI * n / 720.0;
            Vec<2> kh, vh;
            kh << std::cos(th), std::sin(th);
            vh << -std::sin(th), std::cos(th);
            const Mat<2> P = vh * kh.transpose();
            const double e = 1e-3 * g;
            const Mat<2> dT = (l.extra<2>(K + e * P, Mat<2>::Zero()) - l.extra<2>(K - e * P, Mat<2>::Zero())) / (2 * e);
            qmin = std::min(qmin, vh.dot(dT * kh));
          }
          CAPTURE(static_cast<int>(f));
          CAPTURE(k);
          CAPTURE(sign);
          CAPTURE(wi);
          if (kDerivatives[k] == ConvectedDerivative::mixed)
            CHECK(qmin >= l.mu * (1 - 1e-9));
          else
            CHECK(qmin == doctest::Approx(l.mu * (1.0 - wi)).epsilon(1e-6).scale(l.mu));
        }
}
