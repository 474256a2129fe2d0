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

  double begin(const RhsContext<D>&, Index) const { return 0.0; }
  void pair(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, double& acc) const {
    const ParticleSet<D>& p = ctx.particles;
    double vdot = 0;
    for (int a = 0; a < D; ++a) vdot += (p.velocity[D * i + a] - p.velocity[D * nb.j + a]) * nb.rij[a];
    acc += p.mass[nb.j] * vdot * nb.F;
  }
  void end(const RhsContext<D>& ctx, Index i, double& acc) const { ctx.drhodt[i] += acc; }
};

}  // namespace
VESPH_EFFECT_FACTORY(makeContinuity, Continuity)
}  // namespace vesph
