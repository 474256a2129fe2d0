#pragma once
// The artificial stress of Monaghan (2000) and Gray, Monaghan & Swift (2001) as used by
// Fang et al. (2006) §3.2, eqs. (40)-(44), for one particle: from the total stress sigma
// (tension positive) and the density rho,
//   sigma = Q diag(sigma'_a) Q^T                 principal axes (eqs. 41, 43, 44)
//   R'_a  = -eps sigma'_a / rho^2  if sigma'_a > 0,  else 0            (eq. 42)
//   R     = Q diag(R'_a) Q^T                     rotated back (eq. 40)
// R is negative definite where the particle is in tension and zero where it is not: in the
// momentum equation it acts like an extra pressure between near neighbours
// (src/physics/artificial_stress.cpp). 2D: Fang's closed form with the angle of eq. (41);
// 3D: Eigen's SelfAdjointEigenSolver. Only the symmetric part of sigma is used.
#include <Eigen/Eigenvalues>

#include <cmath>

#include "vesph/physics/constitutive.hpp"

namespace vesph {

template <int D>
Mat<D> artificialStress(const Mat<D>& sigma_in, double rho, double eps) {
  const Mat<D> sigma = 0.5 * (sigma_in + sigma_in.transpose());
  const double scale = -eps / (rho * rho);
  if constexpr (D == 2) {
    const double sxx = sigma(0, 0), syy = sigma(1, 1), sxy = sigma(0, 1);
    // Largest principal stress; none in tension: R = 0 without the trigonometry.
    const double mean = 0.5 * (sxx + syy), half = 0.5 * (sxx - syy);
    if (mean + std::sqrt(half * half + sxy * sxy) <= 0) return Mat<D>::Zero();
    const double theta = 0.5 * std::atan2(2.0 * sxy, sxx - syy);  // eq. (41), any quadrant
    const double c = std::cos(theta), s = std::sin(theta);
    const double c2 = c * c, s2 = s * s, cs = c * s;
    const double sp_xx = c2 * sxx + 2.0 * cs * sxy + s2 * syy;  // eq. (43)
    const double sp_yy = s2 * sxx - 2.0 * cs * sxy + c2 * syy;  // eq. (44)
    const double rp_xx = sp_xx > 0 ? scale * sp_xx : 0.0;        // eq. (42)
    const double rp_yy = sp_yy > 0 ? scale * sp_yy : 0.0;
    Mat<D> R;                                                    // eq. (40)
    R(0, 0) = rp_xx * c2 + rp_yy * s2;
    R(1, 1) = rp_xx * s2 + rp_yy * c2;
    R(0, 1) = R(1, 0) = cs * (rp_xx - rp_yy);
    return R;
  } else {
    // Gershgorin: every eigenvalue <= max_a (sigma_aa + sum_b!=a |sigma_ab|); if that is <= 0
    // nothing is in tension (the common case of a pressure-dominated fluid).
    double bound = -1e300;
    for (int a = 0; a < D; ++a) {
      double row = sigma(a, a);
      for (int b = 0; b < D; ++b)
        if (b != a) row += std::abs(sigma(a, b));
      bound = std::max(bound, row);
    }
    if (bound <= 0) return Mat<D>::Zero();
    const Eigen::SelfAdjointEigenSolver<Mat<D>> es(sigma);
    Vec<D> rp;
    for (int a = 0; a < D; ++a) {
      const double sp = es.eigenvalues()[a];
      rp[a] = sp > 0 ? scale * sp : 0.0;
    }
    return es.eigenvectors() * rp.asDiagonal() * es.eigenvectors().transpose();
  }
}

}  // namespace vesph
