// Divergence of the elastic stress in the momentum equation, Fang et al. (2006) eq. (27) for
// the elastic part S of sigma = -p I + 2 eta_s D + S (the pressure and solvent parts are the
// pressure_gradient and viscosity effects):
//   dv_i^a/dt += sum_j m_j (S_i^{ab}/rho_i^2 + S_j^{ab}/rho_j^2) dW_ij/dx_i^b
// Antisymmetric in i, j: conserves linear momentum. Wall particles carry the stress
// extrapolated from the fluid (Fang eq. 46). The stress is read from the field
// "elastic_stress": symmetric (3 components in 2D, 6 in 3D: the rate-type models) or a full
// row-major D x D tensor (the second-order fluid, whose mixed convected derivative is not
// symmetric); the divergence is taken over the second index, (div S)^a = dS^{ab}/dx^b.
// wall_stress = "continued": a wall neighbour enters with the fluid particle's own S_i in place
// of its extrapolated S_j (a constant continuation of each particle's stress into the wall, as
// [effects.viscosity] wall_stress = "continued" does with mu kappa^T). Fang's eq. 46 average over a wall
// particle's fluid neighbours turns through large angles of azimuth beside a thin rod (a radius
// of a few spacings); the continuation does not depend on the wall's shape (docs/theory.md §5.6,
// measured in docs/validation.md §20).
#include "vesph/physics/constitutive.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class StressDivergence final : public PairEffect<D, StressDivergence<D>> {
 public:
  explicit StressDivergence(ConfigTable& cfg)
      : continued_(cfg.choice("wall_stress", "extrapolated", {"extrapolated", "continued"}) == "continued") {}
  std::string_view name() const override { return "stress_divergence"; }
  Phase phase() const override { return Phase::forces; }

  void setup(Setup<D>& s) override {
    stress_ = s.particles.fields.find("elastic_stress");
    if (!stress_)
      throw InputError("effects.stress_divergence needs an elastic stress, which no effect of this scene evolves: "
                       "add a constitutive model such as [effects.oldroyd_b]");
    full_ = stress_->components == D * D;
    if (!full_ && stress_->components != symmetricComponents<D>())
      throw std::logic_error("elastic_stress has an unexpected number of components");
    // Implicit with a model whose linear rate is (Oldroyd-B, UCM): the elastic shear wave, the
    // coupling of this term with (eta_p/lambda)(kappa + kappa^T), is then implicit as a whole
    // (docs/theory.md §9.5). Linear in the evolving stress at frozen positions.
    implicit_ = hasLinearRateModel(*s.effects) ? ImplicitPart::all : ImplicitPart::none;
  }
  ImplicitPart implicitPart() const override { return implicit_; }

  struct Local {
    Vec<D> acc;
    Mat<D> Si_over_rho2;
    double rho_i2;  // rho_i^2: S_i = Si_over_rho2 rho_i^2 for a continued wall neighbour
    const double* S;
    const double* rho;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    const double rho = p.density[i];
    return {Vec<D>::Zero(), load(stress_->data.data(), i) / (rho * rho), rho * rho, stress_->data.data(),
            p.density.data(), p.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double inv_rho = 1.0 / l.rho[nb.j];
    const Mat<D> Sj = load(l.S, nb.j);
    l.acc += (l.m[nb.j] * nb.F) * ((l.Si_over_rho2 + Sj * (inv_rho * inv_rho)) * nb.rij);
  }
  void pairFixed(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& l) const {
    if (!continued_) return pair(ctx, i, nb, l);
    const double inv_rho = 1.0 / l.rho[nb.j];
    l.acc += (l.m[nb.j] * nb.F * (1.0 + l.rho_i2 * inv_rho * inv_rho)) * (l.Si_over_rho2 * nb.rij);
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    if (ctx.part == RhsPart::implicit_diagonal) return;  // it depends on the stress, not on v_i
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  Mat<D> load(const double* S, Index i) const { return loadStress<D>(S, full_, i); }
  const Field* stress_ = nullptr;
  bool continued_ = false;  // wall_stress = "continued"
  bool full_ = false;
  ImplicitPart implicit_ = ImplicitPart::none;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeStressDivergence, StressDivergence)
}  // namespace vesph
