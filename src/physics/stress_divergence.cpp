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
// both_sides_diffusion = b (0 by default): the discrete elastic-viscous stress split ("both-sides
// diffusion", Guenette & Fortin 1995; DEVSS): a viscous stress of the viscosity eta_a = b eta_p
// is taken out of S in the sum above and added back as Morris' Laplacian, the solvent's form
// (viscosity.cpp):
//   dv_i/dt += sum_j m_j (S'_i/rho_i^2 + S'_j/rho_j^2) grad_i W_ij
//            + sum_j m_j 2 eta_a/(rho_i rho_j) F_ij (v_i - v_j),
//   S' = S - eta_a kappa                              (both_sides_form = "gradient", the default)
//   S' = S - eta_a (kappa + kappa^T - tr(kappa) I)    (both_sides_form = "symmetric").
// The added terms cancel in the continuum (div kappa = lap v, and div(kappa + kappa^T - (div v) I)
// = lap v, for any velocity field; the trace term keeps the symmetric split from a negative bulk
// viscosity), not discretely: where the polymer path kappa -> S -> div S is inaccurate (a wall
// whose radius is a few spacings; docs/theory.md §5.6), the viscous part of S goes through the
// Laplacian, which carries it there as the solvent's viscosity does, and only the remainder S'
// (the elastic part, of order Wi, and a viscous rest that the Laplacian's form leaves) through
// eq. 27. A wall neighbour's S' is its extrapolated S less the fluid particle's own viscous part
// (the velocity gradient lives on the fluid only), or S'_i with wall_stress = "continued"; in the
// Laplacian it presents its no-slip velocity, as in the viscous force. At a free surface the
// Laplacian's natural condition is dv/dn = 0: with the gradient form eq. 27's truncated sum on
// eta_a kappa cancels it (for a rigid rotation the split is then the stress form of the viscous
// force, zero with the renormalised gradient), and the surface keeps the traction of S; the
// symmetric form leaves -eta_a (kappa^T - (div v) I).n there (Fang's Oldroyd-B drop fractured
// with it, measured), but beside a wall a few spacings in radius it carries the fluid closer to
// the Newtonian fluid (docs/theory.md §5.6).
#include <algorithm>

#include "vesph/physics/constitutive.hpp"
#include "vesph/physics/morris_laplacian.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

struct NoSplit {};
// What the split's pair loop carries for particle i (both_sides_diffusion > 0 only).
template <int D>
struct SplitOf {
  const double* kappa;   // the velocity gradients (row-major D x D); null: the Jacobian's diagonal
  Mat<D> viscous_i;      // viscous(i): a wall neighbour's too, whose kappa is not computed
  Vec<D> vi;
  double two_eta_over_rhoi;
  const double* v;
  const double* fixed_velocity;  // velocities presented by fixed particles (index j - fixed0)
  std::size_t fixed0;
};

// The split is a template argument: the default pair loop carries nothing of it (the viscous
// force's run-time switch of form cost 4 % of a scene's pair rate: viscosity.cpp).
template <int D, bool Split>
class StressDivergence final : public PairEffect<D, StressDivergence<D, Split>> {
 public:
  StressDivergence(ConfigTable& cfg, double both_sides)
      : continued_(cfg.choice("wall_stress", "extrapolated", {"extrapolated", "continued"}) == "continued"),
        both_sides_(both_sides) {
    if constexpr (Split) {
      gradient_form_ = cfg.choice("both_sides_form", "gradient", {"gradient", "symmetric"}) == "gradient";
    } else if (cfg.has("both_sides_form")) {
      throw InputError("effects.stress_divergence.both_sides_form chooses the split's form: set both_sides_diffusion > 0 "
                       "or remove it");
    }
  }
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
    if constexpr (Split) {
      double eta_p = 0;
      for (const Effect<D>* e : *s.effects) eta_p += e->polymerViscosity();
      if (full_ || !(eta_p > 0))
        throw InputError("effects.stress_divergence.both_sides_diffusion splits the viscous part off the stress of a "
                         "rate-type model with a polymer viscosity (oldroyd_b, ucm, xpp); this scene's stress has "
                         "none: remove both_sides_diffusion");
      eta_a_ = both_sides_ * eta_p;
      nu_total_ = (s.viscosity + eta_a_) / s.rest_density;
      kappa_ = s.particles.fields.find("velocity_gradient");  // required by every rate-type model
      wall_velocity_ = s.particles.fields.find("wall_velocity");
      zero_velocity_.assign(D * s.particles.size(), 0.0);
    }
  }
  void resized(const ParticleSet<D>& particles, const ParticleRemap&) override {
    if constexpr (Split) zero_velocity_.assign(D * particles.size(), 0.0);
  }
  ImplicitPart implicitPart() const override { return implicit_; }
  // The split's Laplacian and its kappa are linear in the velocities: implicit with the rest of
  // the term (the implicit evaluations then compute kappa too).
  bool implicitReadsVelocityGradient() const override { return Split && implicit_ == ImplicitPart::all; }
  // The split's Laplacian is a diffusion of viscosity eta_a on top of the solvent's: the
  // explicit viscous step limit sees the sum (neither when both are implicit).
  void stability(StabilityInputs& in) const override {
    if constexpr (Split) in.kinematic_viscosity = std::max(in.kinematic_viscosity, nu_total_);
  }
  // The Laplacian's rows for arkode-imex's preconditioner, as the viscous force's
  // (viscosity.cpp: the wall neighbours lumped onto the diagonal); the divergence of the split-off
  // stress couples second neighbours and is left to GMRES, as the stress form's is.
  bool couplesVelocities() const override { return Split && implicit_ == ImplicitPart::all; }
  void velocityCoupling(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                        std::span<const Neighbour<D>> fixed, std::span<const double> wall_dependence,
                        VelocityCouplingRow& row) const override {
    morris::addCouplingRow<D>(ctx.particles, i, eta_a_, moving, fixed, wall_dependence, wall_velocity_ != nullptr, row);
  }

  struct Local {
    Vec<D> acc;
    Mat<D> Si_over_rho2;  // S_i / rho_i^2 (S'_i with the split)
    double rho_i2;        // rho_i^2: S_i = Si_over_rho2 rho_i^2 for a continued wall neighbour
    const double* S;
    const double* rho;
    const double* m;
    [[no_unique_address]] std::conditional_t<Split, SplitOf<D>, NoSplit> split;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    const double rho = p.density[i];
    Local l{Vec<D>::Zero(), Mat<D>::Zero(), rho * rho, stress_->data.data(), p.density.data(), p.mass.data(), {}};
    if constexpr (!Split) {
      l.Si_over_rho2 = load(stress_->data.data(), i) / (rho * rho);
    } else {
      SplitOf<D>& sp = l.split;
      sp.two_eta_over_rhoi = 2.0 * eta_a_ / rho;
      if (ctx.part == RhsPart::implicit_diagonal) {
        // The Laplacian's diagonal, sum_j w_ij: the sum below with v_i = 1, every other velocity
        // and every stress zero (the kappa part's self term left out, as the viscous force's).
        sp.kappa = nullptr;
        sp.viscous_i = Mat<D>::Zero();
        sp.vi = Vec<D>::Ones();
        sp.v = zero_velocity_.data();
        sp.fixed_velocity = zero_velocity_.data();
        sp.fixed0 = 0;
        return l;
      }
      sp.kappa = kappa_->data.data();
      sp.viscous_i = viscous(i);
      l.Si_over_rho2 = (load(stress_->data.data(), i) - sp.viscous_i) / (rho * rho);
      sp.vi = p.v(i);
      sp.v = p.velocity.data();
      sp.fixed_velocity = wall_velocity_ ? wall_velocity_->data.data() : p.velocity.data();
      sp.fixed0 = wall_velocity_ ? p.n_moving : 0;
    }
    return l;
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double inv_rho = 1.0 / l.rho[nb.j];
    Mat<D> Sj = load(l.S, nb.j);
    if constexpr (Split) {
      const SplitOf<D>& sp = l.split;
      const double w = morris::weight(l.m[nb.j], sp.two_eta_over_rhoi, l.rho[nb.j], nb.F);
      for (int a = 0; a < D; ++a) l.acc[a] += w * (sp.vi[a] - sp.v[D * nb.j + a]);
      if (!sp.kappa) return;  // the Jacobian's diagonal: the Laplacian's only
      Sj -= viscous(nb.j);
    }
    l.acc += (l.m[nb.j] * nb.F) * ((l.Si_over_rho2 + Sj * (inv_rho * inv_rho)) * nb.rij);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double inv_rho = 1.0 / l.rho[nb.j];
    if constexpr (Split) {
      const SplitOf<D>& sp = l.split;
      const double w = morris::weight(l.m[nb.j], sp.two_eta_over_rhoi, l.rho[nb.j], nb.F);
      for (int a = 0; a < D; ++a) l.acc[a] += w * (sp.vi[a] - sp.fixed_velocity[D * (nb.j - sp.fixed0) + a]);
      if (!sp.kappa) return;
    }
    if (continued_) {
      l.acc += (l.m[nb.j] * nb.F * (1.0 + l.rho_i2 * inv_rho * inv_rho)) * (l.Si_over_rho2 * nb.rij);
      return;
    }
    Mat<D> Sj = load(l.S, nb.j);
    if constexpr (Split) Sj -= l.split.viscous_i;
    l.acc += (l.m[nb.j] * nb.F) * ((l.Si_over_rho2 + Sj * (inv_rho * inv_rho)) * nb.rij);
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    // Without the split the term depends on the stress, not on v_i: no diagonal.
    if (!Split && ctx.part == RhsPart::implicit_diagonal) return;
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  Mat<D> load(const double* S, Index i) const { return loadStress<D>(S, full_, i); }
  // The stress the split moves to the Laplacian (kappa row-major D x D): eta_a kappa_j
  // ("gradient") or eta_a (kappa_j + kappa_j^T - tr(kappa_j) I) ("symmetric"). The divergence of
  // either is eta_a lap v in the continuum for any velocity field, compressible too (without the
  // trace term the symmetric one's would be eta_a (lap v + grad div v), and the split would leave
  // the bulk viscosity -eta_a on the weakly compressible flow's sound waves: the Oldroyd-B
  // start-up at E = 2, beta = 0.1 diverged at 0.35 s, measured).
  Mat<D> viscous(Index j) const {
    const auto kappa = Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(kappa_->data.data() + D * D * j);
    if (gradient_form_) return eta_a_ * kappa;
    return eta_a_ * (kappa + kappa.transpose() - kappa.trace() * Mat<D>::Identity());
  }
  const Field* stress_ = nullptr;
  bool continued_ = false;     // wall_stress = "continued"
  bool gradient_form_ = true;  // both_sides_form = "gradient"
  bool full_ = false;
  ImplicitPart implicit_ = ImplicitPart::none;
  double both_sides_ = 0;  // both_sides_diffusion: eta_a / eta_p
  double eta_a_ = 0;       // the viscosity moved from eq. 27 to the Laplacian, Pa s
  double nu_total_ = 0;    // (eta_s + eta_a) / rho0, m^2/s
  const Field* kappa_ = nullptr;
  const Field* wall_velocity_ = nullptr;
  std::vector<double> zero_velocity_;  // every neighbour velocity, for the Jacobian's diagonal
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> makeStressDivergence(ConfigTable& cfg) {
  // the fraction of eta_p moved to the Laplacian: 1 moves all of it, 0 (the default) none
  const double both_sides = cfg.numberAtMost("both_sides_diffusion", 0.0, Bound::nonnegative, 10.0);
  if (both_sides > 0) return std::make_unique<StressDivergence<D, true>>(cfg, both_sides);
  return std::make_unique<StressDivergence<D, false>>(cfg, 0.0);
}
template std::unique_ptr<Effect<2>> makeStressDivergence<2>(ConfigTable&);
template std::unique_ptr<Effect<3>> makeStressDivergence<3>(ConfigTable&);
}  // namespace vesph
