// The single-equation eXtended Pom-Pom (XPP) model, Verbeeten, Peters & Baaijens, J. Rheol. 45
// (2001) 823 (single-equation form; include/vesph/physics/constitutive/xpp.hpp has the
// equations). As for Oldroyd-B the extra stress is T = 2 eta_s D + tau: the optional solvent
// part is [effects.viscosity] with mu = fluid.viscosity = eta_s; the polymer stress tau is the
// evolving "elastic_stress" (plus "elastic_stress_zz" in 2D, since tau_zz != 0 in planar flow).
//
// Keys: modulus G (Pa) or polymer_viscosity eta_p = G lambda_0b (Pa s), exactly one;
// backbone_relaxation_time lambda_0b (s); stretch_relaxation_time lambda_0s (s) or
// relaxation_ratio r = lambda_0b/lambda_0s, exactly one, with lambda_0s <= lambda_0b (r >= 1:
// the Pom-Pom backbone stretch relaxes faster than its orientation); arms q (a positive whole
// number, nu = 2/q); anisotropy alpha in [0, 1].
#include <cmath>

#include "vesph/physics/constitutive/xpp.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class Xpp final : public ConstitutiveEffect<D, Xpp<D>> {
 public:
  static constexpr bool kOutOfPlaneStress = true;

  explicit Xpp(ConfigTable& cfg) {
    rate_.lambda_b = cfg.number("backbone_relaxation_time", std::nullopt, Bound::positive, "s");
    const auto G = cfg.optionalNumber("modulus", Bound::positive, "Pa");
    const auto eta_p = cfg.optionalNumber("polymer_viscosity", Bound::positive, "Pa s");
    if (G && eta_p)
      cfg.fail("polymer_viscosity", "either modulus G (Pa) or polymer_viscosity eta_p = G * backbone_relaxation_time "
                                    "(Pa s), not both");
    if (!G && !eta_p)
      cfg.fail("modulus", "modulus G (Pa) or polymer_viscosity eta_p = G * backbone_relaxation_time (Pa s): "
                          "one of the two is required");
    rate_.G = G ? *G : *eta_p / rate_.lambda_b;

    if (cfg.has("orientation_relaxation_time"))
      cfg.fail("orientation_relaxation_time",
               "stretch_relaxation_time lambda_0s (s) or relaxation_ratio = lambda_0b/lambda_0s instead of this key "
               "(in the Pom-Pom model lambda_0s is the relaxation time of the backbone stretch; that of the backbone "
               "orientation is lambda_0b, backbone_relaxation_time)");
    const auto lambda_s = cfg.optionalNumber("stretch_relaxation_time", Bound::positive, "s");
    const auto ratio = cfg.optionalNumber("relaxation_ratio", Bound::positive, "-");
    if (lambda_s && ratio)
      cfg.fail("relaxation_ratio", "either stretch_relaxation_time lambda_0s (s) or relaxation_ratio "
                                   "r = lambda_0b/lambda_0s, not both");
    if (!lambda_s && !ratio)
      cfg.fail("stretch_relaxation_time", "stretch_relaxation_time lambda_0s (s) or relaxation_ratio "
                                          "r = lambda_0b/lambda_0s: one of the two is required");
    rate_.r = ratio ? *ratio : rate_.lambda_b / *lambda_s;
    if (!(rate_.r >= 1.0))
      cfg.fail(ratio ? "relaxation_ratio" : "stretch_relaxation_time",
               ratio ? std::string("relaxation_ratio r = lambda_0b/lambda_0s >= 1 (the backbone stretch relaxes "
                                   "faster than its orientation)")
                     : std::string("stretch_relaxation_time lambda_0s <= backbone_relaxation_time lambda_0b (s) (the "
                                   "backbone stretch relaxes faster than its orientation)"));

    const double q = cfg.number("arms", std::nullopt, Bound::positive, "-");
    if (q != std::floor(q)) cfg.fail("arms", "the number of arms q, a positive whole number");
    rate_.nu = 2.0 / q;
    rate_.alpha = cfg.numberIn("anisotropy", std::nullopt, 0.0, 1.0, "-");
  }
  std::string_view name() const override { return "xpp"; }

  template <class K, int E>
  Mat<E> rate(const K& kappa, const Mat<E>& tau) const {
    return rate_.template operator()<E>(kappa, tau);
  }
  double polymerViscosity() const override { return rate_.G * rate_.lambda_b; }
  double relaxationTime() const { return rate_.lambda_b; }
  // The trace of tau relaxes with lambda_0s in the linear limit (and faster, with
  // lambda_s = lambda_0s e^{-nu (Lambda - 1)}, once the backbone is stretched).
  double shortestRelaxationTime() const { return rate_.lambda_b / rate_.r; }

 private:
  XppRate rate_;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeXpp, Xpp)
}  // namespace vesph
