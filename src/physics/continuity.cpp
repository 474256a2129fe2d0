// Continuity equation, Fang et al. (2006) eq. (26):
//   d rho_i/dt = sum_j m_j (v_i - v_j) . grad_i W_ij
// Fixed neighbours contribute with their own (wall) velocity.
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class Continuity final : public PairEffect<D, Continuity<D>> {
 public:
  explicit Continuity(ConfigTable&) {}
  std::string_view name() const override { return "continuity"; }
  Phase phase() const override { return Phase::forces; }

  // Array pointers live in the accumulator so that the pair loop keeps them in registers.
  struct Local {
    double acc;
    Vec<D> vi;
    const double* v;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    return {0.0, p.v(i), p.velocity.data(), p.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    double vdot = 0;
    for (int a = 0; a < D; ++a) vdot += (l.vi[a] - l.v[D * nb.j + a]) * nb.rij[a];
    l.acc += l.m[nb.j] * vdot * nb.F;
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const { ctx.drhodt[i] += l.acc; }
};

}  // namespace
VESPH_EFFECT_FACTORY(makeContinuity, Continuity)
}  // namespace vesph
