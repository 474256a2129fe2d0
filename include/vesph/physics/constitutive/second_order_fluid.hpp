#pragma once
// The second-order fluid, seed thesis §2.3-2.4: pure algebra, no time step, no SPH. Used by
// the effect (src/physics/second_order_fluid.cpp) and by tests/test_second_order_fluid.cpp.
//
// With kappa_ab = dv_a/dx_b and the deformation-rate tensor A = kappa + kappa^T (thesis
// §2.3), the extra stress is T = mu A + eps with the elastic part
//   Rivlin-Ericksen (thesis eq. 2.2):  eps = alpha1 Ahat + alpha2 A.A
//   CEF             (thesis eq. 2.3):  eps = (alpha1/2) Ahat - (alpha1/2 + alpha2) A.A
// and Ahat = DA/Dt + C(kappa, A), one of the convected derivatives of thesis Table 2-1
// (in matrix form, v_{i,k} = kappa_ik):
//   contravariant  C = -kappa A - A kappa^T          (DA_ij/Dt - v_{i,k}A_kj - v_{j,k}A_ik)
//   covariant      C =  kappa^T A + A kappa          (DA_ij/Dt + v_{k,i}A_kj + v_{k,j}A_ik)
//   mixed          C =  kappa A - A kappa^T          (DA_ij/Dt + v_{i,k}A_kj - v_{j,k}A_ik)
//   Jaumann        C = -omega A + A omega,  omega = (kappa - kappa^T)/2
// C is bilinear in (kappa, A). The mixed form adds an antisymmetric tensor: its eps, and T,
// are not symmetric.
//
// The material derivative of A follows from the acceleration a = Dv/Dt by
//   D kappa/Dt = grad(a) - kappa kappa,   (grad a)_ab = da_a/dx_b,
// exact for any smooth motion (d_b of a_a = dv_a/dt + v_c d_c v_a), so
//   DA/Dt = G + G^T - kappa kappa - kappa^T kappa^T,   G = grad(a).
//
// Steady simple shear v_x = g y (kappa_xy = g), where DA/Dt = 0 and T_xy = mu g in every
// form, the normal stresses are (T_zz = eps_zz = 0 in plane flow):
//                     T_xx                   T_yy                   N1 = T_xx - T_yy
//   RE contravariant  (alpha2 - 2 alpha1) g^2  alpha2 g^2             -2 alpha1 g^2
//   RE covariant      alpha2 g^2               (alpha2 + 2 alpha1) g^2 -2 alpha1 g^2
//   RE mixed          alpha2 g^2               alpha2 g^2             0
//   RE Jaumann        (alpha2 - alpha1) g^2    (alpha2 + alpha1) g^2  -2 alpha1 g^2
//   CEF: the same with alpha1 -> alpha1/2, alpha2 -> -(alpha1/2 + alpha2):
//   CEF contravariant -(3 alpha1/2 + alpha2) g^2  -(alpha1/2 + alpha2) g^2   -alpha1 g^2
//   CEF covariant     -(alpha1/2 + alpha2) g^2    (alpha1/2 - alpha2) g^2    -alpha1 g^2
//   CEF mixed         -(alpha1/2 + alpha2) g^2    -(alpha1/2 + alpha2) g^2   0
//   CEF Jaumann       -(alpha1 + alpha2) g^2      -alpha2 g^2                -alpha1 g^2
// (docs/theory.md derives them; tests/test_second_order_fluid.cpp checks the code against them.)
#include <string_view>

#include "vesph/physics/constitutive.hpp"

namespace vesph {

enum class SecondOrderForm { rivlin_ericksen, cef };
enum class ConvectedDerivative { contravariant, covariant, mixed, jaumann };

struct SecondOrderFluidLaw {
  SecondOrderForm form = SecondOrderForm::rivlin_ericksen;
  ConvectedDerivative derivative = ConvectedDerivative::contravariant;
  double mu = 0;      // viscosity, Pa s
  double alpha1 = 0;  // first normal stress coefficient, Pa s^2
  double alpha2 = 0;  // second normal stress coefficient, Pa s^2

  // eps = c1 Ahat + c2 A.A
  double c1() const { return form == SecondOrderForm::rivlin_ericksen ? alpha1 : 0.5 * alpha1; }
  double c2() const { return form == SecondOrderForm::rivlin_ericksen ? alpha2 : -(0.5 * alpha1 + alpha2); }

  // The convective part C(K, A) of the convected derivative (Table 2-1), bilinear in (K, A).
  template <int D>
  Mat<D> convective(const Mat<D>& K, const Mat<D>& A) const {
    switch (derivative) {
      case ConvectedDerivative::contravariant: return -K * A - A * K.transpose();
      case ConvectedDerivative::covariant: return K.transpose() * A + A * K;
      case ConvectedDerivative::mixed: return K * A - A * K.transpose();
      case ConvectedDerivative::jaumann: {
        const Mat<D> omega = 0.5 * (K - K.transpose());
        return -omega * A + A * omega;
      }
    }
    return Mat<D>::Zero();
  }

  // DA/Dt from the velocity gradient and the acceleration gradient G = grad(a).
  template <int D>
  static Mat<D> materialDerivative(const Mat<D>& K, const Mat<D>& G) {
    return G + G.transpose() - K * K - K.transpose() * K.transpose();
  }

  // The elastic part eps for a given DA/Dt.
  template <int D>
  Mat<D> elastic(const Mat<D>& K, const Mat<D>& DA) const {
    const Mat<D> A = K + K.transpose();
    return c1() * (DA + convective<D>(K, A)) + c2() * (A * A);
  }

  // The extra stress T = mu A + eps.
  template <int D>
  Mat<D> extra(const Mat<D>& K, const Mat<D>& DA) const {
    return mu * (K + K.transpose()) + elastic<D>(K, DA);
  }

  // Derivative of eps along one direction c, by the product rule: given dK = d(kappa)/dx_c
  // and dDA = d(DA/Dt)/dx_c. Exact (eps is a polynomial of degree two in kappa).
  template <int D>
  Mat<D> elasticDerivative(const Mat<D>& K, const Mat<D>& dK, const Mat<D>& dDA) const {
    const Mat<D> A = K + K.transpose(), dA = dK + dK.transpose();
    return c1() * (dDA + convective<D>(dK, A) + convective<D>(K, dA)) + c2() * (dA * A + A * dA);
  }

  // d(DA/Dt)/dx_c from dK = d(kappa)/dx_c and dG = d(grad a)/dx_c.
  template <int D>
  static Mat<D> materialDerivativeDerivative(const Mat<D>& K, const Mat<D>& dK, const Mat<D>& dG) {
    return dG + dG.transpose() - (dK * K + K * dK) - (dK.transpose() * K.transpose() + K.transpose() * dK.transpose());
  }
};

}  // namespace vesph
