#pragma once
// The kernel-gradient correction of Randles & Libersky (1996), shared by the renormalised
// pressure gradient (the pressure_gradient effect, form = "renormalised") and the ISPH
// projection's gradient rows (src/isph/pressure_gradient_rows.cpp):
//   M_i = -sum_j V_j F_ij r_ij r_ij^T      (the identity on a full support, to quadrature error)
//   grad f_i = M_i^-1 sum_j V_j (f_j - f_i) F_ij r_ij   exact for linear f on any support.
// Where M_i is near-singular (an isolated particle, a filament: smallest eigenvalue below 0.1)
// the inverse would amplify noise; the uncorrected sum (M = I) is used there.
#include <Eigen/Cholesky>

#include "vesph/core/types.hpp"

namespace vesph {

template <int D>
Eigen::Matrix<double, D, D> renormalisationInverse(const Eigen::Matrix<double, D, D>& M) {
  using Mat = Eigen::Matrix<double, D, D>;
  // The smallest eigenvalue of the symmetric M is above 0.1 exactly when M - 0.1 I is positive
  // definite, which a Cholesky factorisation tells at a fraction of an eigenvalue solve's cost
  // (the test runs once per particle and evaluation: on the 3D jet at D = 4 dx, whose velocity
  // gradient is renormalised, the eigenvalue solve took 10 % of the step; docs/performance.md).
  const Eigen::LLT<Mat> shifted(M - 0.1 * Mat::Identity());
  return shifted.info() == Eigen::Success ? Mat(M.inverse()) : Mat(Mat::Identity());
}

}  // namespace vesph
