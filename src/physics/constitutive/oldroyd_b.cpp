// Oldroyd-B and upper-convected Maxwell (UCM) models, Fang et al. (2006) eqs. (5)-(9), (28):
// the extra stress splits into a Newtonian solvent part 2 eta_s D (the [effects.viscosity]
// term with mu = fluid.viscosity = eta_s) and an elastic part S obeying
//   dS/dt = kappa S + S kappa^T - S/lambda + (eta_p/lambda)(kappa + kappa^T)       (Fang 28)
// with the polymer viscosity eta_p and relaxation time lambda. In Fang's notation
// (total viscosity eta, lambda_1, lambda_2): lambda = lambda_1, eta_p = eta (1 - lambda_2/lambda_1),
// eta_s = eta lambda_2/lambda_1. UCM is lambda_2 = 0: no solvent (fluid.viscosity = 0, no
// [effects.viscosity]).
#include "vesph/physics/constitutive/oldroyd_b.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class OldroydB : public ConstitutiveEffect<D, OldroydB<D>> {
 public:
  explicit OldroydB(ConfigTable& cfg, bool ucm = false) : ucm_(ucm) {
    rate_.lambda = cfg.number("relaxation_time", std::nullopt, Bound::positive, "s");
    rate_.eta_p = cfg.number("polymer_viscosity", std::nullopt, Bound::positive, "Pa s");
  }
  std::string_view name() const override { return ucm_ ? "ucm" : "oldroyd_b"; }

  void setup(Setup<D>& s) override {
    if (ucm_ && s.viscosity != 0.0)
      throw InputError("effects.ucm: the upper-convected Maxwell model has no solvent viscosity; set "
                       "fluid.viscosity = 0 and drop [effects.viscosity] (or use [effects.oldroyd_b])");
    ConstitutiveEffect<D, OldroydB<D>>::setup(s);
  }

  template <class K>
  Mat<D> rate(const K& kappa, const Mat<D>& S) const {
    return rate_.template operator()<D>(kappa, S);
  }
  double polymerViscosity() const override { return rate_.eta_p; }
  double relaxationTime() const { return rate_.lambda; }
  // The part of the rate linear in kappa and S, implicit under arkode-imex (ConstitutiveEffect).
  template <class K>
  Mat<D> linearRate(const K& kappa, const Mat<D>& S) const {
    return rate_.template linearPart<D>(kappa, S);
  }

 private:
  bool ucm_;
  OldroydBRate rate_;
};

template <int D>
class Ucm final : public OldroydB<D> {
 public:
  explicit Ucm(ConfigTable& cfg) : OldroydB<D>(cfg, true) {}
};

}  // namespace
VESPH_EFFECT_FACTORY(makeOldroydB, OldroydB)
VESPH_EFFECT_FACTORY(makeUcm, Ucm)
}  // namespace vesph
