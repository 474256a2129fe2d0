// XSPH particle movement (Monaghan 1989; thesis §3.6): the particles move with a velocity
// smoothed over their neighbours, which keeps them in order; the momentum equation keeps v.
//   form = "monaghan" (default; Monaghan's XSPH):
//     dx_i/dt = v_i + eps sum_j (m_j / rho_ij) (v_j - v_i) W_ij,   rho_ij = (rho_i + rho_j)/2
//   form = "normalised" (the thesis' §3.6 formula, a Shepard average):
//     dx_i/dt = v_i - eps sum_j v_ij W_ij / sum_j W_ij,   v_ij = v_i - v_j
//     where the denominator includes j = i (the thesis sums j = 1..N), W(0).
// On a uniform lattice sum_j (m_j/rho_j) W_ij = 1 (self included), so the two agree in the bulk
// and differ where the neighbourhood is truncated (free surface), where the normalised form
// keeps the full weight eps. The "monaghan" weights m_i m_j W_ij / rho_ij are symmetric in
// i, j, so sum_i m_i (dx_i/dt - v_i) = 0: the centre of mass moves with the total momentum.
// Only moving neighbours enter (walls do not move; wall particles are not averaged in). The
// thesis uses eps = 0.5. The ODE system sets dx/dt = v before the force pass; this effect adds
// the correction. Positions only: continuity and momentum use v.
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class Xsph final : public PairEffect<D, Xsph<D>> {
 public:
  explicit Xsph(ConfigTable& cfg)
      : eps_(cfg.numberIn("epsilon", 0.5, 0.0, 1.0)),
        normalised_(cfg.choice("form", "monaghan", {"monaghan", "normalised"}) == "normalised") {}
  std::string_view name() const override { return "xsph"; }
  Phase phase() const override { return Phase::forces; }
  bool needsKernelValue() const override { return true; }
  std::string_view form() const override { return normalised_ ? "normalised" : "monaghan"; }

  void setup(Setup<D>& s) override { w0_ = s.kernel.W(0.0); }

  struct Local {
    Vec<D> acc;   // sum_j weight_j (v_j - v_i)
    double sumW;  // normalised form: sum_j W_ij over moving neighbours and i itself
    Vec<D> vi;
    double rhoi;
    const double* v;
    const double* rho;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    return {Vec<D>::Zero(), w0_, p.v(i), p.density[i], p.velocity.data(), p.density.data(), p.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    double w;
    if (normalised_) {
      w = nb.W;
      l.sumW += nb.W;
    } else {
      w = 2.0 * l.m[nb.j] * nb.W / (l.rhoi + l.rho[nb.j]);
    }
    for (int a = 0; a < D; ++a) l.acc[a] += w * (l.v[D * nb.j + a] - l.vi[a]);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>&, Local&) const {}
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    const double s = normalised_ ? eps_ / l.sumW : eps_;
    for (int a = 0; a < D; ++a) ctx.dxdt[D * i + a] += s * l.acc[a];
  }

 private:
  double eps_;
  bool normalised_;
  double w0_ = 0;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeXsph, Xsph)
}  // namespace vesph
