// Artificial stress against the tensile instability, Fang et al. (2006) §3.2, eqs. (38)-(44)
// (Monaghan 2000; Gray, Monaghan & Swift 2001). Fang's eq. (38) adds f_ij^n (R_i + R_j) to the
// stress term of the momentum equation (27):
//   dv_i/dt += sum_j m_j f_ij^n (R_i + R_j) . grad_i W_ij = sum_j m_j f_ij^n F_ij (R_i + R_j) x_ij
//   f_ij = W(r_ij) / W(dx)                                                        (39)
// with dx the initial particle spacing (Setup::spacing) and R the artificial stress of each
// particle (vesph/physics/artificial_stress.hpp, eqs. 40-44) from its total stress
//   sigma_i = -p_i I + S_i.
// p_i is the field "pressure" (the equation of state, p0 included: a background pressure
// keeps the fluid out of tension, as it should), S_i the field "elastic_stress" when a
// viscoelastic model evolves one (its symmetric part for the second-order fluid's full
// tensor), otherwise zero. The solvent stress 2 eta_s D of Fang's tau (their eq. 8) is left out:
// here it is the Morris Laplacian of [effects.viscosity], a pair force along v_ij rather than
// the (sigma_i/rho_i^2 + sigma_j/rho_j^2) . grad W form of eq. (27) whose attraction in
// tension is the instability that R counters; and a Newtonian scene has no velocity gradient.
// The pair term is antisymmetric in i, j: linear momentum is conserved.
//
// R of every particle is needed before the pair pass (each pair reads R_j): it is computed by
// Effect::prepare into the field "artificial_stress" for ALL particles. Wall particles get R
// from their own pressure (the wall treatment's extrapolated p_w, ρ_w) and their interpolated S
// (Fang eq. 46): the same sigma_w that the pressure and stress terms use for them, so the
// wall-fluid pairs are treated like fluid-fluid pairs. f_ij^n needs W: the pass evaluates it.
#include <cmath>

#include "vesph/physics/artificial_stress.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class ArtificialStress final : public PairEffect<D, ArtificialStress<D>> {
 public:
  explicit ArtificialStress(ConfigTable& cfg)
      : eps_(cfg.numberIn("epsilon", 0.2, 0.0, 1.0)),
        n_(static_cast<int>(cfg.integer("exponent", 4, 1, 16))) {}
  std::string_view name() const override { return "artificial_stress"; }
  Phase phase() const override { return Phase::forces; }
  bool needsKernelValue() const override { return true; }
  bool prepares() const override { return true; }

  void setup(Setup<D>& s) override {
    pressure_ = s.particles.fields.find("pressure");
    if (!pressure_)
      throw InputError("effects.artificial_stress needs the particle pressure, which nothing in this "
                       "scene provides: add [effects.equation_of_state]");
    stress_ = s.particles.fields.find("elastic_stress");
    if (stress_) {
      full_ = stress_->components == D * D;
      if (!full_ && stress_->components != symmetricComponents<D>())
        throw std::logic_error("elastic_stress has an unexpected number of components");
    }
    const double w_dx = s.kernel.W(s.spacing);
    if (!(w_dx > 0))
      throw InputError("effects.artificial_stress: the kernel vanishes at the particle spacing (W(dx) = 0), "
                       "so f_ij = W(r)/W(dx) of Fang eq. (39) is undefined; use a larger smoothing_ratio");
    inv_w_dx_ = 1.0 / w_dx;
    R_ = &s.particles.fields.require("artificial_stress", symmetricComponents<D>(), Field::Range::all);
  }

  void prepare(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    const ParticleSet<D>& p = ctx.particles;
    const double* pres = pressure_->data.data();
    double* R = R_->data.data();
    constexpr int nc = symmetricComponents<D>();
    for (std::size_t k = begin; k < end; ++k) {
      Mat<D> sigma = -pres[k] * Mat<D>::Identity();
      if (stress_ && (k < p.n_moving || stress_->range == Field::Range::all)) sigma += load(k);
      packSymmetric<D>(artificialStress<D>(sigma, p.density[k], eps_), R + nc * k);
    }
  }

  struct Local {
    Vec<D> acc;
    Mat<D> Ri;
    const double* R;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    constexpr int nc = symmetricComponents<D>();
    return {Vec<D>::Zero(), unpackSymmetric<D>(R_->data.data() + nc * i), R_->data.data(), ctx.particles.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    constexpr int nc = symmetricComponents<D>();
    const double f = nb.W * inv_w_dx_;  // eq. (39)
    double fn = f;
    for (int k = 1; k < n_; ++k) fn *= f;
    const Mat<D> Rij = l.Ri + unpackSymmetric<D>(l.R + nc * nb.j);
    l.acc += (l.m[nb.j] * fn * nb.F) * (Rij * nb.rij);
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  Mat<D> load(std::size_t k) const { return loadStress<D>(stress_->data.data(), full_, k); }

  double eps_;
  int n_;
  double inv_w_dx_ = 0;
  const Field* pressure_ = nullptr;
  const Field* stress_ = nullptr;
  bool full_ = false;
  Field* R_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeArtificialStress, ArtificialStress)
}  // namespace vesph
