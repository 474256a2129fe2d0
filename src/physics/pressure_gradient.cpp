// Pressure force per unit mass, -grad(p)/rho, in one of two SPH forms:
//   symmetric  (thesis eq. 3.18, Fang eq. 27):
//       dv_i/dt = - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij
//     conserves linear momentum exactly (antisymmetric in i, j); the default.
//   difference (thesis eq. 3.17):
//       dv_i/dt = - (1/rho_i) sum_j (m_j/rho_j) (p_j - p_i) grad_i W_ij
//     exact for linear pressure fields up to the lattice quadrature factor of the kernel
//     (|m - 1| ~ 5e-4 for the quintic kernel at h = 1.6 dx, tests/test_operators.cpp);
//     not momentum conserving.
//   renormalised (Randles & Libersky 1996): the difference form with the kernel-gradient
//     correction M_i^-1, M_i = -sum_j (m_j/rho_j) F_ij r_ij r_ij^T:
//       dv_i/dt = -(1/rho_i) M_i^-1 sum_j (m_j/rho_j) (p_j - p_i) grad_i W_ij
//     exact for linear pressure fields on any support (free surfaces, walls); M_i = I where it
//     is near-singular (smallest eigenvalue below 0.1). The form of the ISPH projection's
//     correction (include/vesph/isph/projection.hpp), which makes the incremental projection
//     keep a fluid at rest exactly at rest. Not momentum conserving.
// Wall particles carry the pressure and density given them by the wall treatment.
// dry_walls = "omit" (symmetric and difference forms): a wall or dummy particle whose pressure
// is negative is left out of the sum. Adami's extrapolation continues the hydrostatic pressure
// p_f + rho_f g.(x_w - x_f) above the free surface, where it is negative: such a "dry" wall
// particle fills the kernel of the surface particle beside the wall where a free surface has no
// neighbour, and the pair term holds that particle below the free surface's level (a 2D tank at
// rest: the column beside a wall that rises above the water settles 0.05 dx low, +0.014 dx with
// this option; docs/validation.md §20, session 21). Off by default: it also removes the pull of a
// wall on fluid in tension beside it (a die's lip), and the push of a dry wall particle on fluid
// that climbs the wall above the level where its extrapolated pressure turns negative (measured:
// a climb along a turning rod held back by 0.03-0.05 dx; validation.md §20, session 22).
// free_surface_mirror = true (needs [effects.free_surface]): for a particle flagged on the free
// surface, the zero-pressure condition by mirrored dummy particles, thesis eq. (4.1): with
// p_i = 0 and a mirror image of every neighbour carrying -p_j,
//       dv_i/dt = - (2/rho_i) sum_j (m_j/rho_j) p_j grad_i W_ij
// in place of the form above.
#include <cstdint>
#include <limits>

#include "vesph/core/renormalisation.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

// Mirror: whether the scene asked for the free-surface mirror; a template parameter so that
// scenes without it run the pair loop of before, with no per-pair test.
template <int D, bool Mirror>
class PressureGradientT final : public PairEffect<D, PressureGradientT<D, Mirror>> {
 public:
  explicit PressureGradientT(ConfigTable& cfg)
      : symmetric_(cfg.string("form", "symmetric") == "symmetric"),
        omit_dry_walls_(cfg.choice("dry_walls", "include", {"include", "omit"}) == "omit") {}
  std::string_view name() const override { return "pressure_gradient"; }
  Phase phase() const override { return Phase::forces; }
  std::string_view form() const override { return symmetric_ ? "symmetric" : "difference"; }

  void setup(Setup<D>& s) override {
    pressure_ = s.particles.fields.find("pressure");
    if (!pressure_)
      throw InputError("effects.pressure_gradient needs the particle pressure, which nothing in this "
                       "scene provides: add [effects.equation_of_state] (weakly compressible SPH)");
    if constexpr (Mirror) {
      surface_ = s.particles.fields.find("free_surface");
      if (!surface_)
        throw InputError("effects.pressure_gradient.free_surface_mirror needs the free-surface flags: add "
                         "[effects.free_surface]");
    }
  }

  // Array pointers live in the accumulator so that the pair loop keeps them in registers.
  struct Local {
    Vec<D> acc;
    bool surface;
    double pi, rhoi, pi_over_rho2;
    const double* p;
    const double* rho;
    const double* m;
    std::size_t first_fixed;  // wall particles are [first_fixed, ...): with dry_walls = "omit"
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& ps = ctx.particles;
    const double p = pressure_->data[i], rho = ps.density[i];
    bool surface = false;
    if constexpr (Mirror) surface = surface_->data[i] > 0.5;
    // Without dry_walls = "omit" no index is >= first_fixed: the pair test below never holds.
    const std::size_t first_fixed = omit_dry_walls_ ? ps.n_moving : std::numeric_limits<std::size_t>::max();
    return {Vec<D>::Zero(), surface, p, rho, p / (rho * rho), pressure_->data.data(), ps.density.data(), ps.mass.data(),
            first_fixed};
  }
  void pair(const RhsContext<D>& ctx, Index, const Neighbour<D>& nb, Local& l) const {
    const double pj = l.p[nb.j], inv_rhoj = 1.0 / l.rho[nb.j], mj = l.m[nb.j];
    if (nb.j >= l.first_fixed && pj < 0 &&
        ctx.particles.kind[nb.j] != static_cast<std::uint8_t>(ParticleKind::inflow))
      return;  // a dry wall particle (dry_walls = "omit", above)
    double coef = symmetric_ ? mj * (l.pi_over_rho2 + pj * inv_rhoj * inv_rhoj) : mj * inv_rhoj * (pj - l.pi) / l.rhoi;
    if constexpr (Mirror)
      if (l.surface) coef = 2.0 * mj * inv_rhoj * pj / l.rhoi;
    l.acc -= (coef * nb.F) * nb.rij;
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  bool symmetric_;
  bool omit_dry_walls_;
  const Field* pressure_ = nullptr;
  const Field* surface_ = nullptr;
};

template <int D>
class RenormalisedPressureGradient final : public PairEffect<D, RenormalisedPressureGradient<D>> {
 public:
  explicit RenormalisedPressureGradient(ConfigTable&) {}
  std::string_view name() const override { return "pressure_gradient"; }
  Phase phase() const override { return Phase::forces; }
  std::string_view form() const override { return "renormalised"; }

  void setup(Setup<D>& s) override {
    pressure_ = s.particles.fields.find("pressure");
    if (!pressure_)
      throw InputError("effects.pressure_gradient needs the particle pressure, which nothing in this scene provides: add "
                       "[effects.equation_of_state] (weakly compressible SPH) or set solver.scheme = \"isph\"");
  }

  using Mat = Eigen::Matrix<double, D, D>;
  struct Local {
    Mat M;
    Vec<D> raw;
    double pi;
    const double* p;
    const double* rho;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& ps = ctx.particles;
    return {Mat::Zero(), Vec<D>::Zero(), pressure_->data[i], pressure_->data.data(), ps.density.data(), ps.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double vf = l.m[nb.j] / l.rho[nb.j] * nb.F;
    l.M -= vf * nb.rij * nb.rij.transpose();
    l.raw += (vf * (l.p[nb.j] - l.pi)) * nb.rij;
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    const Vec<D> grad = renormalisationInverse<D>(l.M) * l.raw;
    const double inv_rho = 1.0 / ctx.particles.density[i];
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] -= grad[a] * inv_rho;
  }

 private:
  const Field* pressure_ = nullptr;
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> makePressureGradient(ConfigTable& cfg) {
  const std::string form = cfg.choice("form", "symmetric", {"symmetric", "difference", "renormalised"});
  if (form == "renormalised") {
    if (cfg.boolean("free_surface_mirror", false))
      cfg.fail("free_surface_mirror", "false with form = \"renormalised\" (the renormalised gradient is exact at the free surface without mirrors)");
    return std::make_unique<RenormalisedPressureGradient<D>>(cfg);
  }
  if (cfg.boolean("free_surface_mirror", false)) return std::make_unique<PressureGradientT<D, true>>(cfg);
  return std::make_unique<PressureGradientT<D, false>>(cfg);
}
template std::unique_ptr<Effect<2>> makePressureGradient<2>(ConfigTable&);
template std::unique_ptr<Effect<3>> makePressureGradient<3>(ConfigTable&);
}  // namespace vesph
