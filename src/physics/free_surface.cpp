// Free-surface detection by the particle number density, thesis §4.2:
//   n_i = sum_j W(r_ij, h)   (the particle itself included, W(0))
//   particle i is on the free surface when n_i <= threshold * n_ref   (threshold 0.8)
// The kernel support of a particle at or near the surface is truncated, so its number density
// drops. The thesis takes n_ref = max_i n_i; here n_ref is the number density of a particle
// with a full support on the initial lattice (computed once at setup), which is what max_i n_i
// is in any flow with one interior particle, without a global reduction inside the right-hand
// side (and so the flag of a particle does not depend on particles far away). Wall particles
// count as neighbours (a fluid particle on a wall is not on the free surface).
// Writes "number_density" (moving particles) and "free_surface" (1 on the surface, 0 inside;
// all particles, walls 0), which the output stores. Used by the pressure gradient's mirrored
// zero-pressure treatment (thesis eq. 4.1, effects.pressure_gradient.free_surface_mirror).
#include <cmath>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class FreeSurface final : public PairEffect<D, FreeSurface<D>> {
 public:
  explicit FreeSurface(ConfigTable& cfg) {
    threshold_ = cfg.numberIn("threshold", 0.8, 0.05, 0.99, "of the full-support number density");
  }
  std::string_view name() const override { return "free_surface"; }
  Phase phase() const override { return Phase::gradients; }
  bool needsKernelValue() const override { return true; }

  void setup(Setup<D>& s) override {
    density_ = &s.particles.fields.require("number_density", 1, Field::Range::moving);
    flag_ = &s.particles.fields.require("free_surface", 1, Field::Range::all);
    // n_ref: the lattice sum of W over a full support, spacing dx, the particle itself included.
    const double support = s.kernel.supportRadius(), dx = s.spacing;
    const int reach = static_cast<int>(std::ceil(support / dx));
    double n = 0;
    s.kernel.visit([&](auto shape) {
      using Shape = decltype(shape);
      std::array<int, D> k;
      k.fill(-reach);
      while (true) {
        double r2 = 0;
        for (int a = 0; a < D; ++a) r2 += (k[a] * dx) * (k[a] * dx);
        const double r = std::sqrt(r2);
        if (r < support) n += s.kernel.w_scale * Shape::f(r / s.kernel.h);
        int a = 0;
        while (a < D && ++k[a] > reach) k[a++] = -reach;
        if (a == D) break;
      }
    });
    limit_ = threshold_ * n;
    self_ = s.kernel.visit([&](auto shape) { return s.kernel.w_scale * decltype(shape)::f(0.0); });
  }

  struct Local {
    double n;
  };
  Local begin(const RhsContext<D>&, Index) const { return {self_}; }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const { l.n += nb.W; }
  void end(const RhsContext<D>&, Index i, Local& l) const {
    density_->data[i] = l.n;
    flag_->data[i] = l.n <= limit_ ? 1.0 : 0.0;
  }

 private:
  double threshold_ = 0.8, limit_ = 0, self_ = 0;
  Field* density_ = nullptr;
  Field* flag_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeFreeSurface, FreeSurface)
}  // namespace vesph
