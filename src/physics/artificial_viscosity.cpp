// Monaghan's artificial viscosity, Fang et al. (2006) §3.1, eqs. (30)-(37):
//   Pi_ij = (-alpha c_ij phi_ij + beta phi_ij^2) / rho_ij   if v_ij . x_ij < 0     (31)
//   Pi_ij = 0                                                 otherwise          (32)
//   phi_ij = h v_ij . x_ij / (|x_ij|^2 + 0.01 h^2)                                 (33)
//   c_ij = (c_i + c_j)/2 = c,  rho_ij = (rho_i + rho_j)/2,  v_ij = v_i - v_j,
//   x_ij = x_i - x_j                                                             (34)-(37)
// and, with Pi_ij acting as a pressure (Monaghan 1992; see below on the sign):
//   dv_i/dt -= sum_j m_j Pi_ij grad_i W_ij = - sum_j m_j Pi_ij F_ij x_ij
// Pi_ij is symmetric in i, j and grad_i W_ij antisymmetric: linear momentum is conserved.
//
// The sign. Fang's eq. (30) adds + Pi_ij delta to sigma_i/rho_i^2 + sigma_j/rho_j^2 with
// sigma = -p I + ..., i.e. Pi_ij would enter like a negative pressure; with Pi_ij >= 0 for
// approaching pairs (phi_ij < 0) that would pull them together and feed kinetic energy. The
// dissipative term (and Monaghan's original, where it is added to p_i/rho_i^2 + p_j/rho_j^2)
// is the one written above: an extra pressure between approaching particles.
//
// c is the sound speed of the scene's pressure closure (PressureModel::soundSpeed, uniform in
// WCSPH, so c_ij = c). ISPH has no sound speed: there c is the key sound_speed, a numerical
// signal speed that only sets the dissipation nu = alpha c h / (2 (D + 2)) (the ISPH drop
// takes Fang's 12.5 m/s, so that it carries the WCSPH drop's dissipation; without the alpha
// term it fractured, as Fang §4.1 found for the viscoelastic drop). Wall neighbours enter with the wall's extrapolated no-slip velocity
// (field "wall_velocity", as in the viscous term: the mirror image of the fluid velocity
// through the wall surface, so that a particle approaching the wall meets an approaching
// image), the density the wall treatment gave them and their mass.
#include <cmath>
#include <optional>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class ArtificialViscosity final : public PairEffect<D, ArtificialViscosity<D>> {
 public:
  explicit ArtificialViscosity(ConfigTable& cfg)
      // The defaults are the usual ones for water (DualSPHysics' alpha = 0.01 with no beta term,
      // Crespo et al. 2015 §3.2): Monaghan's O(1) values (Fang et al. take alpha = 1, beta = 2 for
      // their drops, whose scenes state them) damp a water flow at c ~ 10-100 m/s about a hundred
      // times too much (docs/theory.md "Artificial viscosity"). The limit of 100 keeps an absurd
      // value from driving the viscous step limit to zero.
      : alpha_(cfg.numberAtMost("alpha", 0.01, Bound::nonnegative, 100.0)),
        beta_(cfg.numberAtMost("beta", 0.0, Bound::nonnegative, 100.0)),
        signal_speed_(cfg.optionalNumber("sound_speed", Bound::positive, "m/s")) {}
  std::string_view name() const override { return "artificial_viscosity"; }
  Phase phase() const override { return Phase::forces; }

  void setup(Setup<D>& s) override {
    // The pressure closure is set up in the state phase, before this force effect: its sound
    // speed is final here (also when chosen by the rule of thesis eq. 3.38).
    if (signal_speed_) {
      if (s.pressure_model)
        throw InputError("effects.artificial_viscosity.sound_speed: only in scenes without an equation of state "
                         "(the WCSPH sound speed is the equation of state's); remove the key");
      c_ = *signal_speed_;
    } else {
      if (!s.pressure_model)
        throw InputError("effects.artificial_viscosity needs the sound speed of an equation of state, which "
                         "nothing in this scene provides: add [effects.equation_of_state], or (ISPH) give "
                         "effects.artificial_viscosity.sound_speed");
      c_ = s.pressure_model->soundSpeed();
    }
    h_ = s.kernel.h;
    eta2_ = 0.01 * h_ * h_;
    wall_velocity_ = s.particles.fields.find("wall_velocity");
  }
  // For the explicit step limits: the alpha term is, in the continuum limit and summed over
  // all pairs, a viscosity nu = alpha c h / (2 (D + 2)) (Monaghan 2005, Rep. Prog. Phys. 68:1703,
  // for any radial kernel); an upper bound since only approaching pairs contribute.
  void stability(StabilityInputs& in) const override {
    in.kinematic_viscosity = std::max(in.kinematic_viscosity, alpha_ * c_ * h_ / (2.0 * (D + 2)));
  }

  struct Local {
    Vec<D> acc;
    Vec<D> vi;
    double rhoi;
    const double* v;
    const double* rho;
    const double* m;
    const double* fixed_velocity;  // velocities presented by fixed particles (index j - fixed0)
    std::size_t fixed0;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    const double* fv = wall_velocity_ ? wall_velocity_->data.data() : p.velocity.data();
    const std::size_t fixed0 = wall_velocity_ ? p.n_moving : 0;
    return {Vec<D>::Zero(), p.v(i), p.density[i], p.velocity.data(), p.density.data(), p.mass.data(), fv, fixed0};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    add(nb, l, l.v + D * nb.j);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    add(nb, l, l.fixed_velocity + D * (nb.j - l.fixed0));
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += l.acc[a];
  }

 private:
  void add(const Neighbour<D>& nb, Local& l, const double* vj) const {
    double vx = 0;
    for (int a = 0; a < D; ++a) vx += (l.vi[a] - vj[a]) * nb.rij[a];
    if (vx >= 0) return;                                            // eq. (32)
    const double phi = h_ * vx / (nb.r * nb.r + eta2_);             // eq. (33)
    const double rho_bar = 0.5 * (l.rhoi + l.rho[nb.j]);            // eq. (35)
    const double Pi = (-alpha_ * c_ * phi + beta_ * phi * phi) / rho_bar;  // eq. (31)
    l.acc -= (l.m[nb.j] * Pi * nb.F) * nb.rij;
  }

  double alpha_, beta_;
  std::optional<double> signal_speed_;
  double c_ = 0, h_ = 1, eta2_ = 0;
  const Field* wall_velocity_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeArtificialViscosity, ArtificialViscosity)
}  // namespace vesph
