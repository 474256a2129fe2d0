// Density diffusion, the "delta-SPH" term of Molteni & Colagrossi (2009, Comput. Phys. Commun.
// 180:861-872): a diffusive term in the continuity equation that damps the acoustic noise of
// weakly compressible SPH (the spurious high-frequency pressure and the tension that an impact
// pulse leaves behind when it reflects from a free surface):
//   d rho_i/dt += delta h c sum_j psi_ij . grad_i W_ij  m_j/rho_j,
//   psi_ij = 2 (rho_j - rho_i) r_ji / |r_ij|^2,   r_ji = x_j - x_i
// with delta a dimensionless coefficient (0.1 in Molteni & Colagrossi and in Antuono et al.
// 2010, Comput. Phys. Commun. 181:532), h the smoothing length and c the sound speed of the
// scene's pressure closure (PressureModel::soundSpeed). With grad_i W_ij = F_ij r_ij and
// r_ji = -r_ij the pair term is psi_ij . grad_i W_ij = -2 (rho_j - rho_i) F_ij: the 1/|r_ij|^2
// cancels, so there is no singularity at r -> 0. The sum is Brookshaw's SPH Laplacian,
// sum_j 2 (f_j - f_i) (-F_ij) m_j/rho_j ~ lap f: a density diffusivity delta h c, which vanishes
// with h (the scheme stays consistent) and, with delta = 0.1, is far below the explicit limit
// of the sound speed (reported to the step limits like a kinematic viscosity, see stability()).
//
// Hydrostatic correction (Antuono, Colagrossi & Marrone 2012, Comput. Phys. Commun. 183:2570,
// showed that the Molteni form does not preserve a hydrostatic state near a free surface: on a
// truncated kernel the sum of a linear density field does not vanish, and the term then pushes
// the density away from hydrostatics there. Fourtakas et al. 2019, Comput. Fluids 190:346, cure
// it by diffusing only the dynamic part rho - rho^H). With a body acceleration g the hydrostatic
// state is p^H = const + rho0 g . x, so with the linear equation of state (dp/drho = c^2)
//   rho^H_j - rho^H_i = rho0 g . (x_j - x_i) / c^2 = -rho0 g . r_ij / c^2
// and the term acts on (rho_j - rho_i) - (rho^H_j - rho^H_i) = rho_j - rho_i + rho0 g . r_ij / c^2.
// The correction is linear in r_ij, so in a full kernel it sums to zero and changes nothing;
// it matters only where the support is truncated (free surface, walls when skipped). Key
// hydrostatic = true (default); without a body acceleration it is zero. It assumes the fluid's
// own acceleration is small against g; a body in free fall (the drop before impact) has no
// hydrostatic gradient, and there the correction drives its surface particles at a rate of
// order delta c rho0 |g| / c^2 (about 80 kg/m^3/s, i.e. 0.2 % of rho0 over the 0.03 s fall of
// the drop case), which is what the uncorrected term does to a fluid at rest.
//
// Walls ("walls" key). "skip" (default): only moving (fluid) neighbours enter. Fixed particles
// carry a density from the wall extrapolation (Adami et al. 2012, vesph/boundary/dummy_walls.hpp),
// not from the continuity equation; the one-sided sum then is a zero-flux (Neumann) condition
// for the dynamic density at the wall, consistent with the wall's own condition grad p = rho g
// at a wall at rest (which the hydrostatic correction removes exactly), and the term stays
// conservative among the fluid particles: the pair weights 2 (-F_ij) V_i V_j are symmetric, so
//   sum_i (m_i/rho_i) d rho_i/dt = 0
// (with equal masses: sum_i d ln rho_i/dt = 0). "include": wall neighbours enter like fluid ones
// with their extrapolated density (and the hydrostatic correction, which the wall extrapolation
// also contains): the full support near the wall, at the price of exchanging density with
// particles whose density is not evolved.
//
// form = "antuono" (Antuono, Colagrossi, Marrone & Molteni 2010, Comput. Phys. Commun. 181:532,
// their delta-SPH): the pair vector carries the renormalised density gradients,
//   psi_ij = 2 (rho_j - rho_i) r_ji / |r_ij|^2 - (<grad rho>_i + <grad rho>_j),
//   <grad rho>_i = M_i^-1 sum_j V_j (rho_j - rho_i) F_ij r_ij   (vesph/core/renormalisation.hpp),
// so the pair term is psi_ij . grad_i W_ij = -[2 (rho_j - rho_i) + (g_i + g_j) . r_ij] F_ij.
// For a quadratic density with exact gradients (g_j = g_i + H r_ji) the bracket is zero pair by
// pair: the term leaves linear and quadratic densities alone and acts on what the gradients
// miss and on the fourth derivatives (~ delta h c h^2 lap^2 rho in a full support) instead of
// Molteni's delta h c lap rho. Why it matters: a steady flow's dynamic density is not harmonic
// (a rotating flow's centrifugal pressure), and Molteni's Laplacian of it is a steady source
// that the continuity equation balances by moving the fluid, against the pressure the flow
// needs; the free surface then stands at the wrong height (the rod climbing's fall at the rod,
// docs/validation.md §20). The renormalised gradient is exact for a linear density on any
// support (M_i from the same neighbours: fluid only, or with walls = "include" the walls too),
// so a hydrostatic state is kept at a free surface without the hydrostatic correction; with it
// (the default) both the differences and the gradients are of the dynamic density, which
// changes nothing but at particles where M_i is near-singular (then the plain sum, M = I). The
// gradients are a sum of their own, in the gradients pass (gradientsPart(); field
// "density_gradient", D per moving particle), so that every neighbour's is there, ghosts
// included, when the pair term runs. A wall neighbour (walls = "include") takes g_j = g_i.
// The pair term stays antisymmetric, so sum_i V_i d rho_i/dt = 0 as with Molteni's.
//
// The total volume sum_i m_i/rho_i is not exactly conserved: d/dt sum V_i from this term is
// -sum_pairs delta h c 2 (-F_ij) V_i V_j (rho_j - rho_i)^2/(rho_i rho_j) <= 0, second order in the
// density fluctuations (without the hydrostatic correction).
#include <algorithm>

#include "vesph/core/renormalisation.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

// (rho_j - rho_i) - (rho^H_j - rho^H_i) = rho_j - rho_i + rho0 g . r_ij / c^2, the pair's difference
// of the dynamic density (hydrostatic_gradient = rho0 g / c^2, zero without the correction).
template <int D>
double dynamicDifference(double rhoj, double rhoi, const Vec<D>& hydrostatic_gradient, const Vec<D>& rij) {
  return rhoj - rhoi + hydrostatic_gradient.dot(rij);
}

// The renormalised gradient of the dynamic density, the gradients pass of the "antuono" form
// (owned and set up by DensityDiffusion<D, true>).
template <int D>
class DensityGradient final : public PairEffect<D, DensityGradient<D>> {
 public:
  std::string_view name() const override { return "density_diffusion (density gradient)"; }
  Phase phase() const override { return Phase::gradients; }
  void configure(Field* gradient, const Vec<D>& hydrostatic_gradient, bool include_walls) {
    gradient_ = gradient;
    hydrostatic_gradient_ = hydrostatic_gradient;
    include_walls_ = include_walls;
  }

  struct Local {
    Vec<D> g;                        // sum_j V_j (rho_j - rho_i)_dynamic F_ij r_ij
    Eigen::Matrix<double, D, D> M;   // -sum_j V_j F_ij r_ij r_ij^T
    double rhoi;
    const double* rho;
    const double* m;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    return {Vec<D>::Zero(), Eigen::Matrix<double, D, D>::Zero(), p.density[i], p.density.data(), p.mass.data()};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const double w = l.m[nb.j] / l.rho[nb.j] * nb.F;
    l.g += (w * dynamicDifference<D>(l.rho[nb.j], l.rhoi, hydrostatic_gradient_, nb.rij)) * nb.rij;
    l.M.noalias() -= w * nb.rij * nb.rij.transpose();
  }
  void pairFixed(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& l) const {
    if (include_walls_) pair(ctx, i, nb, l);
  }
  void end(const RhsContext<D>&, Index i, Local& l) const {
    const Vec<D> g = renormalisationInverse<D>(l.M) * l.g;
    double* out = gradient_->data.data() + D * i;
    for (int a = 0; a < D; ++a) out[a] = g[a];
  }

 private:
  Field* gradient_ = nullptr;
  Vec<D> hydrostatic_gradient_ = Vec<D>::Zero();
  bool include_walls_ = false;
};

template <int D, bool Antuono>
class DensityDiffusion final : public PairEffect<D, DensityDiffusion<D, Antuono>> {
 public:
  explicit DensityDiffusion(ConfigTable& cfg)
      // delta-SPH takes delta ~ 0.1 (Molteni & Colagrossi 2009); beyond 10 the diffusion's step
      // limit would only shrink the step towards zero.
      : delta_(cfg.numberAtMost("delta", 0.1, Bound::nonnegative, 10.0)),
        hydrostatic_(cfg.boolean("hydrostatic", true)),
        include_walls_(cfg.choice("walls", "skip", {"skip", "include"}) == "include") {}
  std::string_view name() const override { return "density_diffusion"; }
  std::string_view form() const override { return Antuono ? "antuono" : "molteni"; }
  Phase phase() const override { return Phase::forces; }
  Effect<D>* gradientsPart() override { return Antuono ? &gradient_pass_ : nullptr; }

  void setup(Setup<D>& s) override {
    // The pressure closure is set up in the state phase, before this force effect: its sound
    // speed is final here (also when chosen by the rule of thesis eq. 3.38).
    if (!s.pressure_model)
      throw InputError("effects.density_diffusion needs the sound speed of an equation of state, which "
                       "nothing in this scene provides: add [effects.equation_of_state]");
    c_ = s.pressure_model->soundSpeed();
    h_ = s.kernel.h;
    coefficient_ = delta_ * h_ * c_;
    // rho^H_j - rho^H_i = -(rho0 / c^2) g . r_ij
    hydrostatic_gradient_ = Vec<D>::Zero();
    if (hydrostatic_) hydrostatic_gradient_ = (s.rest_density / (c_ * c_)) * s.body_acceleration;
    if constexpr (Antuono) {
      gradient_ = &s.particles.fields.require("density_gradient", D, Field::Range::moving);
      gradient_pass_.configure(gradient_, hydrostatic_gradient_, include_walls_);
    }
  }
  // The term is a diffusion of density with diffusivity delta h c (Brookshaw's Laplacian, see
  // above): its explicit limit dt <= C h^2 / (delta h c) has the form of the viscous one. The
  // "antuono" form has the same on a density oscillating from particle to particle, which its
  // gradients do not see.
  void stability(StabilityInputs& in) const override {
    in.kinematic_viscosity = std::max(in.kinematic_viscosity, coefficient_);
  }

  struct Local {
    double acc;  // sum_j [2 (rho_j - rho_i + rho0 g . r_ij / c^2) + (g_i + g_j) . r_ij] (-F_ij) m_j/rho_j
    double rhoi;
    const double* rho;
    const double* m;
    Vec<D> gi;          // antuono: <grad rho>_i
    const double* grad; // antuono: the field "density_gradient"
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    if constexpr (Antuono) {
      const double* grad = gradient_->data.data();
      return {0.0, p.density[i], p.density.data(), p.mass.data(), Eigen::Map<const Vec<D>>(grad + D * i), grad};
    } else {
      return {0.0, p.density[i], p.density.data(), p.mass.data(), Vec<D>::Zero(), nullptr};
    }
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    add(l, nb, Antuono ? l.grad + D * nb.j : nullptr);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    if (include_walls_) add(l, nb, l.gi.data());  // a wall particle has no gradient: g_j = g_i
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const { ctx.drhodt[i] += coefficient_ * l.acc; }

 private:
  double delta_;
  bool hydrostatic_;
  bool include_walls_;
  double c_ = 0, h_ = 1, coefficient_ = 0;
  Vec<D> hydrostatic_gradient_ = Vec<D>::Zero();
  Field* gradient_ = nullptr;
  DensityGradient<D> gradient_pass_;

  // Neighbour j's term; gj: its density gradient (antuono only).
  void add(Local& l, const Neighbour<D>& nb, const double* gj) const {
    const double rhoj = l.rho[nb.j];
    double difference = 2.0 * dynamicDifference<D>(rhoj, l.rhoi, hydrostatic_gradient_, nb.rij);
    if constexpr (Antuono) difference += (l.gi + Eigen::Map<const Vec<D>>(gj)).dot(nb.rij);
    l.acc -= difference * nb.F * l.m[nb.j] / rhoj;
  }
};

}  // namespace

template <int D>
std::unique_ptr<Effect<D>> makeDensityDiffusion(ConfigTable& cfg) {
  // "molteni": Molteni & Colagrossi's Laplacian of the density (the default, as before);
  // "antuono": with the renormalised density gradients (above)
  if (cfg.choice("form", "molteni", {"molteni", "antuono"}) == "antuono")
    return std::make_unique<DensityDiffusion<D, true>>(cfg);
  return std::make_unique<DensityDiffusion<D, false>>(cfg);
}
template std::unique_ptr<Effect<2>> makeDensityDiffusion<2>(ConfigTable&);
template std::unique_ptr<Effect<3>> makeDensityDiffusion<3>(ConfigTable&);
}  // namespace vesph
