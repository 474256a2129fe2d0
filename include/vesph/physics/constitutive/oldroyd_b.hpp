#pragma once
// The Oldroyd-B / UCM rate function, Fang et al. (2006) eq. (28): pure, no time step.
//   dS/dt = kappa S + S kappa^T - S/lambda + (eta_p/lambda)(kappa + kappa^T)
// kappa_ab = dv_a/dx_b; S the elastic (polymer) stress; lambda the relaxation time; eta_p the
// polymer viscosity. Used by the effect (src/physics/constitutive/oldroyd_b.cpp) and by the
// homogeneous-flow tests.
#include "vesph/physics/constitutive.hpp"

namespace vesph {

struct OldroydBRate {
  double lambda = 1;  // s
  double eta_p = 0;   // Pa s

  template <int D, class K>
  Mat<D> operator()(const K& kappa, const Mat<D>& S) const {
    return kappa * S + S * kappa.transpose() - S / lambda + (eta_p / lambda) * (kappa + kappa.transpose());
  }
  // The part linear in kappa and S: relaxation and polymer stretching by the flow
  // (implicit under arkode-imex, docs/theory.md §9.5).
  template <int D, class K>
  Mat<D> linearPart(const K& kappa, const Mat<D>& S) const {
    return -S / lambda + (eta_p / lambda) * (kappa + kappa.transpose());
  }
};

}  // namespace vesph
