#pragma once
// The single-equation eXtended Pom-Pom (XPP) rate function: pure, no time step.
//
// Reference: W. M. H. Verbeeten, G. W. M. Peters, F. P. T. Baaijens, "Differential constitutive
// equations for polymer melts: the extended Pom-Pom model", J. Rheol. 45 (2001) 823-843,
// section III ("single equation" form of the XPP model); restated in their J. Non-Newtonian
// Fluid Mech. 108 (2002) 301-326, section 2, and used for SPH by Xu et al. (2013) (seed 003).
// The equation numbers of the printed paper could not be checked here; the equations below
// were verified instead by deriving them from the double-equation XPP (orientation S with the
// Giesekus-type anisotropy, backbone stretch Lambda, tau = G (3 Lambda^2 S - I)): see
// docs/theory.md §5.8.
//
//   upper-convected derivative:   tau^nabla + lambda(tau)^{-1} . tau = 2 G D
//   lambda(tau)^{-1} . tau = (1/lambda_0b) [ (alpha/G) tau.tau + F tau + G (F - 1) I ]
//   F = f(tau)^{-1} = 2 r e^{nu (Lambda - 1)} (1 - 1/Lambda)
//                     + (1/Lambda^2) [ 1 - alpha tr(tau.tau) / (3 G^2) ]
//   Lambda = sqrt(1 + tr(tau)/(3 G)),   nu = 2/q,   r = lambda_0b/lambda_0s
// so, with kappa_ab = dv_a/dx_b (tau^nabla = dtau/dt - kappa tau - tau kappa^T, D = sym kappa):
//   dtau/dt = kappa tau + tau kappa^T - (1/lambda_0b)[ (alpha/G) tau.tau + F tau + G (F - 1) I ]
//             + G (kappa + kappa^T)
// G = eta_p/lambda_0b the plateau modulus, lambda_0b the backbone orientation relaxation time,
// lambda_0s the backbone stretch relaxation time (lambda_s = lambda_0s e^{-nu (Lambda - 1)}),
// q the number of arms, alpha the anisotropy (Giesekus-type) parameter. In the linear limit
// (small tau) the deviatoric part of tau relaxes with lambda_0b and its trace with lambda_0s:
// eta_p = G lambda_0b and Psi_1 = 2 eta_p lambda_0b at vanishing shear rate, as for UCM.
//
// tr and tau.tau are those of the 3x3 tensor: in planar (2D) flow tau_zz != 0 for XPP (F != 1
// in flow), so the 2D effect evaluates this function on the 3x3 tensor (constitutive.hpp).
//
// Lambda^2 = tr(tau/G + I)/3 is a third of the trace of the conformation tensor, positive for
// every physical state. A state with tr(tau) <= -3 G has lost positive definiteness (a
// numerical failure upstream): the function throws NumericalFailure rather than clamping.
#include <cmath>
#include <sstream>

#include "vesph/physics/constitutive.hpp"

namespace vesph {

struct XppRate {
  double lambda_b = 1;  // lambda_0b, backbone orientation relaxation time, s
  double G = 1;         // modulus G = eta_p/lambda_0b, Pa
  double r = 2;         // lambda_0b/lambda_0s, -
  double nu = 1;        // 2/q, -
  double alpha = 0;     // anisotropy, -

  // Lambda^2 = 1 + tr(tau)/(3 G); throws NumericalFailure when it is not positive.
  double stretchSquared(double trace) const {
    const double L2 = 1.0 + trace / (3.0 * G);
    if (L2 <= 0.0) {
      std::ostringstream os;
      os << "XPP: tr(tau) = " << trace << " Pa <= -3G = " << -3.0 * G
         << " Pa, so the backbone stretch Lambda = sqrt(1 + tr(tau)/(3G)) is undefined: the conformation "
            "tensor tau/G + I has lost positive definiteness (under-resolved flow or too large a time step)";
      throw NumericalFailure(os.str());
    }
    return L2;
  }

  // F = f(tau)^{-1} of the relaxation term, from tr(tau) and tr(tau.tau).
  double relaxationFactor(double trace, double trace_sq) const {
    const double L2 = stretchSquared(trace);
    const double L = std::sqrt(L2);
    return 2.0 * r * std::exp(nu * (L - 1.0)) * (1.0 - 1.0 / L) + (1.0 - alpha * trace_sq / (3.0 * G * G)) / L2;
  }

  // dtau/dt for a symmetric E x E tau. The solver always calls it with E = 3 (in 2D with the
  // planar kappa and tau embedded, tau_zz included); E = 2 would drop tau_zz from the traces.
  template <int E, class K>
  Mat<E> operator()(const K& kappa, const Mat<E>& tau) const {
    const Mat<E> tt = tau * tau;
    const double F = relaxationFactor(tau.trace(), tt.trace());
    const Mat<E> relax = (alpha / G) * tt + F * tau + (G * (F - 1.0)) * Mat<E>::Identity();
    return kappa * tau + tau * kappa.transpose() - relax / lambda_b + G * (kappa + kappa.transpose());
  }
};

}  // namespace vesph
