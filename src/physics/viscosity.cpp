// Newtonian viscous force per unit mass by the SPH Laplacian of thesis eq. (3.37), in the
// momentum-conserving form of Morris et al. (1997) eq. (8):
//   dv_i/dt = sum_j  m_j (mu_i + mu_j) / (rho_i rho_j) * F_ij * (v_i - v_j)
// with F_ij = (dW/dr)/r. For constant mu this is (mu/rho_i) times eq. (3.37) with the
// neighbour volume m_j/rho_j. Morris et al. write F r^2/(r^2 + eta^2) with eta^2 = 0.01 h^2 to
// guard r -> 0; that factor lowers the effective viscosity by 0.93 % (its kernel average is
// 0.9907) and set a floor of about 1 % under the Poiseuille error at every resolution
// (docs/studies.md). It is not needed: F = f'(q)/(q h) stays finite as r -> 0 for every kernel
// here, and coincident particles (r = 0) are skipped by the pair driver.
// Next to a wall the neighbour velocity is the wall's extrapolated no-slip velocity
// (field "wall_velocity", vesph/boundary), which places the no-slip condition on the wall
// surface rather than on the wall particles.
//
// form = "stress" (docs/theory.md §5.4 "The viscous free surface"): the divergence of the full
// viscous stress, div(mu (grad v + grad v^T)) = mu lap v + div(mu grad v^T), with the first part
// in Morris' form above and the second by the symmetric divergence of
// thesis eq. (3.18) on mu kappa^T (kappa the velocity gradient of Fang eq. 23):
//   dv_i/dt += sum_j m_j (mu kappa_i^T/rho_i^2 + mu kappa_j^T/rho_j^2) grad_i W_ij.
// Inside the fluid the second part is mu grad(div v), which vanishes for an incompressible
// flow. Where the kernel is cut by a free surface, each sum's missing neighbours leave a force on
// a boundary term: the Laplacian's on mu dv/dn (its natural condition is dv/dn = 0, which a
// rigid rotation or a swelling jet violates), the two together on the traction
// mu (grad v + grad v^T).n, which with the pressure's makes the stress-free condition
// (-p I + tau).n = 0 of a viscous free surface (for a linear velocity field the two sums add
// up to the symmetric divergence of tau exactly). Morris' part keeps its damping of the
// particle-scale velocity noise, which a divergence of kappa alone does not see (the nested
// first derivatives' zero-energy modes: with tau = mu (kappa + kappa^T) in eq. 3.18 alone the
// die's extrudate fell apart, measured). Wall particles enter Morris' part with their no-slip
// velocity (the wall friction). In the kappa^T part they are left out by default
// (wall_stress = "omitted"), so a wall acts on that sum as a free surface and puts mu kappa^T.n
// on the rows beside it: zero at a flat wall with the flow along it, a drag beside a turning rod.
// wall_stress = "continued" lets them enter with the fluid particle's own mu kappa_i^T (a
// constant continuation into the wall), which removes that term where the walls fill the kernel
// but, at a die's lip (wall, free surface and the lip's large kappa in one kernel), peels the
// extrudate's surface rows off (theory §5.4, measured).
// wall_stress = "continued_where_full" applies that continuation only where fluid and walls fill
// the kernel: the wall terms are summed apart and scaled by f = clamp((S - 0.85)/0.12, 0, 1),
// S = sum_j V_j W_ij over fluid and wall neighbours and the particle itself (the Shepard sum,
// V_j = m_j/rho_j; 1 in a full kernel). Beside a wall the fluid covers (a rod, a die's inner
// rows) it is "continued"; where a free surface cuts the kernel as well (the lip's surface rows,
// whose continued term 2 mu kappa_i^T sum_wall V_j grad W has nothing on the free side to balance
// it) it is "omitted", with a linear blend between (docs/notes/die_swell.md, session 13 and 14).
// Only this option asks the pair driver for the kernel value W (needsKernelValue).
#include <algorithm>
#include <string>

#include "vesph/physics/constitutive.hpp"  // Mat<D>
#include "vesph/physics/morris_laplacian.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

struct Nothing {};
template <int D>
struct TransposedStressOf {
  Mat<D> i_over_rho2;    // mu kappa_i^T / rho_i^2
  double rho_i2;         // rho_i^2: a continued wall neighbour carries mu kappa_i^T = i_over_rho2 rho_i^2
  const double* kappa;   // the velocity gradients (row-major D x D); null: the term is left out
  // wall_stress = "continued_where_full" only: the continued wall terms, summed apart, and the
  // Shepard sum S that scales them in end().
  Vec<D> wall_acc;
  double shepard;
};

enum class WallStress { omitted, continued, continued_where_full };

// The form is a template argument: the Laplacian's pair loop carries nothing of the stress form
// (a run-time switch cost 4 % of the Poiseuille scene's pair rate).
template <int D, bool StressForm>
class Viscosity final : public PairEffect<D, Viscosity<D, StressForm>> {
 public:
  explicit Viscosity(ConfigTable& cfg) {
    if constexpr (StressForm) {
      const std::string w =
          cfg.choice("wall_stress", "omitted", {"omitted", "continued", "continued_where_full"});
      wall_stress_ = w == "continued"              ? WallStress::continued
                     : w == "continued_where_full" ? WallStress::continued_where_full
                                                   : WallStress::omitted;
    } else if (cfg.has("wall_stress")) {
      throw InputError("effects.viscosity.wall_stress applies to the stress form's kappa^T sum: set form = \"stress\" "
                       "or remove it");
    }
  }
  std::string_view name() const override { return "viscosity"; }
  Phase phase() const override { return Phase::forces; }
  std::string_view form() const override { return StressForm ? "stress" : "laplacian"; }
  // The Shepard sum of "continued_where_full" reads W; the other options do not pay for it.
  bool needsKernelValue() const override { return blended(); }

  void setup(Setup<D>& s) override {
    // fluid.viscosity defaults to 0 (an inviscid scene needs none): this term needs it set.
    if (!(s.viscosity > 0))
      throw InputError("effects.viscosity needs the viscosity mu: set fluid.viscosity > 0 (Pa s), or remove "
                       "[effects.viscosity] for an inviscid fluid");
    mu_ = s.viscosity;
    nu_ = s.viscosity / s.rest_density;
    if constexpr (StressForm) {
      kappa_ = s.particles.fields.find("velocity_gradient");  // set up before: gradients phase
      if (!kappa_)
        throw InputError("effects.viscosity.form = \"stress\" needs the velocity gradient: add [effects.velocity_gradient]");
    }
    wall_velocity_ = s.particles.fields.find("wall_velocity");
    zero_velocity_.assign(D * s.particles.size(), 0.0);
  }
  void resized(const ParticleSet<D>& particles, const ParticleRemap&) override {
    zero_velocity_.assign(D * particles.size(), 0.0);
  }
  void stability(StabilityInputs& in) const override {
    in.kinematic_viscosity = std::max(in.kinematic_viscosity, nu_);
  }
  // Linear in the velocities (the wall velocities are extrapolated from them): implicit under
  // arkode-imex and semi-implicit, which lifts the viscous step limit (docs/theory.md
  // "Implicit-explicit integration"). The stress form is linear too: its kappa, which the
  // gradients phase computes from the evaluation's velocities, is then computed in the implicit
  // evaluations as well (the velocity gradient's ImplicitPart::shared).
  ImplicitPart implicitPart() const override { return ImplicitPart::all; }
  bool implicitReadsVelocityGradient() const override { return StressForm; }

  // d(dv_i/dt)/dv_j = -w_ij for a fluid neighbour j, and the diagonal sum_j w_ij
  // (morris::addCouplingRow). A wall
  // neighbour b's velocity is extrapolated from the fluid's, v_b = ... + sum_f c_bf v_f (the
  // no-slip mirror: c_bf = -W_bf / sum W), so its term w_ib (v_i - v_b) adds -w_ib c_bf to
  // every such f's column. Those entries are lumped onto the diagonal, w_ib (1 - sum_f c_bf)
  // (2 w_ib for the mirror): the row sums stay exact, and the matrix keeps the signs of an
  // M-matrix, which BoomerAMG needs (with the entries in place, of the opposite sign to the
  // fluid's, its V-cycle let GMRES fail on the die swell; lumped, GMRES takes 2.9 times fewer
  // iterations there than with the Jacobi preconditioner: docs/performance.md).
  // The stress form adds the Laplacian's rows only: the divergence of mu kappa^T couples second
  // neighbours and vanishes inside an incompressible flow (mu grad div v), so the preconditioner
  // leaves it to GMRES.
  bool couplesVelocities() const override { return true; }
  void velocityCoupling(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                        std::span<const Neighbour<D>> fixed, std::span<const double> wall_dependence,
                        VelocityCouplingRow& row) const override {
    morris::addCouplingRow<D>(ctx.particles, i, mu_, moving, fixed, wall_dependence, wall_velocity_ != nullptr, row);
  }

  // Array pointers live in the accumulator so that the pair loop keeps them in registers.
  struct Local {
    Vec<D> acc;
    Vec<D> vi;
    double two_mu_over_rhoi;
    const double* v;
    const double* rho;
    const double* m;
    const double* fixed_velocity;  // velocities presented by fixed particles (index j - n_fixed0)
    std::size_t fixed0;
    [[no_unique_address]] std::conditional_t<StressForm, TransposedStressOf<D>, Nothing> transposed;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    const double* fv = wall_velocity_ ? wall_velocity_->data.data() : p.velocity.data();
    const std::size_t fixed0 = wall_velocity_ ? p.n_moving : 0;
    if (ctx.part == RhsPart::implicit_diagonal) {
      // The Jacobian's diagonal d(dv_i/dt)/dv_i = sum_j w_ij (negative: F < 0) is the sum below
      // with v_i = 1 and every v_j = 0 (the wall velocities' dependence on v_i through the
      // extrapolation left out; the stress form's kappa^T part left out: its self term,
      // -sum_j V_j grad W_ij inside kappa_i times sum_j m_j grad W_ij, vanishes where the kernel
      // is whole).
      Local l{Vec<D>::Zero(), Vec<D>::Ones(), 2.0 * mu_ / p.density[i], zero_velocity_.data(), p.density.data(),
              p.mass.data(), zero_velocity_.data(), 0, {}};
      if constexpr (StressForm) l.transposed = {Mat<D>::Zero(), 0.0, nullptr, Vec<D>::Zero(), 0.0};
      return l;
    }
    Local l{Vec<D>::Zero(), p.v(i), 2.0 * mu_ / p.density[i], p.velocity.data(), p.density.data(), p.mass.data(), fv, fixed0, {}};
    if constexpr (StressForm) {
      const double rho = p.density[i];
      // The Shepard sum starts with the self term V_i W(0): the pair loop skips r = 0.
      const double self = blended() ? p.mass[i] / rho * ctx.kernel.W(0.0) : 0.0;
      l.transposed = {transposedStress(kappa_->data.data(), i) / (rho * rho), rho * rho, kappa_->data.data(),
                      Vec<D>::Zero(), self};
    }
    return l;
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double w = weight(nb, l);
    for (int a = 0; a < D; ++a) l.acc[a] += w * (l.vi[a] - l.v[D * nb.j + a]);
    if constexpr (StressForm) {  // eq. (3.18) on mu kappa^T; grad_i W_ij = F_ij r_ij
      if (!l.transposed.kappa) return;  // the Jacobian's diagonal: the Laplacian's only
      const double inv_rho = 1.0 / l.rho[nb.j];
      if (blended()) l.transposed.shepard += l.m[nb.j] * inv_rho * nb.W;
      l.acc += (l.m[nb.j] * nb.F) *
               ((l.transposed.i_over_rho2 + transposedStress(l.transposed.kappa, nb.j) * (inv_rho * inv_rho)) * nb.rij);
    }
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double w = weight(nb, l);
    for (int a = 0; a < D; ++a) l.acc[a] += w * (l.vi[a] - l.fixed_velocity[D * (nb.j - l.fixed0) + a]);
    if constexpr (StressForm) {  // eq. (3.18) with the wall's mu kappa^T continued as mu kappa_i^T
      if (wall_stress_ == WallStress::omitted || !l.transposed.kappa) return;
      const double inv_rho = 1.0 / l.rho[nb.j];
      const Vec<D> term =
          (l.m[nb.j] * nb.F * (1.0 + l.transposed.rho_i2 * inv_rho * inv_rho)) * (l.transposed.i_over_rho2 * nb.rij);
      if (blended()) {
        l.transposed.shepard += l.m[nb.j] * inv_rho * nb.W;
        l.transposed.wall_acc += term;
      } else {
        l.acc += term;
      }
    }
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    if constexpr (StressForm) {
      if (blended() && l.transposed.kappa) {
        // Full kernel (S >= 0.97): the whole continuation; cut by a free surface (S <= 0.85):
        // none, the wall acts as in "omitted"; linear between.
        const double f = std::clamp((l.transposed.shepard - kFullFrom) / kFullWidth, 0.0, 1.0);
        l.acc += f * l.transposed.wall_acc;
      }
    }
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  double weight(const Neighbour<D>& nb, const Local& l) const {
    return morris::weight(l.m[nb.j], l.two_mu_over_rhoi, l.rho[nb.j], nb.F);
  }
  // mu kappa^T of particle j (kappa^{ab} = dv^a/dx^b, stored row-major: its transpose is the
  // same numbers read column-major).
  Mat<D> transposedStress(const double* kappa, Index j) const {
    return mu_ * Eigen::Map<const Mat<D>>(kappa + D * D * j);
  }

  bool blended() const {
    if constexpr (StressForm) return wall_stress_ == WallStress::continued_where_full;
    return false;
  }
  // "continued_where_full": f = clamp((S - kFullFrom) / kFullWidth, 0, 1). A lattice row at a
  // flat free surface has S near 0.5 to 0.6, a full lattice kernel S = 1 within a few per mille.
  static constexpr double kFullFrom = 0.85, kFullWidth = 0.12;

  const Field* kappa_ = nullptr;
  WallStress wall_stress_ = WallStress::omitted;  // the stress form's wall neighbours in the kappa^T sum
  double mu_ = 0, nu_ = 0;
  const Field* wall_velocity_ = nullptr;
  std::vector<double> zero_velocity_;  // all neighbour velocities, for the Jacobian's diagonal
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> makeViscosity(ConfigTable& cfg) {
  if (cfg.choice("form", "laplacian", {"laplacian", "stress"}) == "stress")
    return std::make_unique<Viscosity<D, true>>(cfg);
  return std::make_unique<Viscosity<D, false>>(cfg);
}
template std::unique_ptr<Effect<2>> makeViscosity<2>(ConfigTable&);
template std::unique_ptr<Effect<3>> makeViscosity<3>(ConfigTable&);
}  // namespace vesph
