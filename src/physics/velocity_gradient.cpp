// Velocity gradient at every moving particle, Fang et al. (2006) eq. (23):
//   kappa_i^{ab} = dv^a/dx^b = sum_j (m_j/rho_j) (v_j^a - v_i^a) dW_ij/dx_i^b
// (the difference form, exact for a uniform velocity). Next to a wall the neighbour velocity is
// the wall's extrapolated no-slip velocity, as in the viscous term. Stored row-major in the
// field "velocity_gradient" (D*D per moving particle) for the constitutive models.
// form = "renormalised": the kernel-gradient correction of Randles & Libersky (1996),
// kappa_i = K_i M_i^-1 with M_i = -sum_j V_j F_ij r_ij r_ij^T over every neighbour, fluid and
// wall (vesph/core/renormalisation.hpp): exact for a linear velocity on any particle
// arrangement (rings of unequal masses around a thin rod, docs/validation.md §20).
#include "vesph/core/renormalisation.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class VelocityGradient final : public PairEffect<D, VelocityGradient<D>> {
 public:
  explicit VelocityGradient(ConfigTable& cfg)
      : renormalised_(cfg.choice("form", "standard", {"standard", "renormalised"}) == "renormalised") {}
  std::string_view name() const override { return "velocity_gradient"; }
  Phase phase() const override { return Phase::gradients; }

  void setup(Setup<D>& s) override {
    kappa_ = &s.particles.fields.require("velocity_gradient", D * D, Field::Range::moving);
    wall_velocity_ = s.particles.fields.find("wall_velocity");
    // The implicit part of an Oldroyd-B/UCM rate (docs/theory.md §9.5) and the stress form of the
    // viscous force read kappa.
    implicit_ = implicitPartReadsVelocityGradient(*s.effects) ? ImplicitPart::shared : ImplicitPart::none;
  }
  ImplicitPart implicitPart() const override { return implicit_; }

  struct Local {
    Eigen::Matrix<double, D, D> k;
    Eigen::Matrix<double, D, D> M;  // renormalised: -sum_j V_j F_ij r_ij r_ij^T
    Vec<D> vi;
    const double* v;
    const double* rho;
    const double* m;
    const double* fixed_velocity;
    std::size_t fixed0;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    const double* fv = wall_velocity_ ? wall_velocity_->data.data() : p.velocity.data();
    return {Eigen::Matrix<double, D, D>::Zero(), Eigen::Matrix<double, D, D>::Zero(), p.v(i), p.velocity.data(), p.density.data(), p.mass.data(), fv,
            wall_velocity_ ? p.n_moving : 0};
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    add(l, l.v + D * nb.j, nb);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    add(l, l.fixed_velocity + D * (nb.j - l.fixed0), nb);
  }
  void end(const RhsContext<D>&, Index i, Local& l) const {
    if (renormalised_) l.k = l.k * renormalisationInverse<D>(l.M);  // M symmetric: row a is M^-1 grad v^a
    double* out = kappa_->data.data() + D * D * i;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) out[D * a + b] = l.k(a, b);
  }

 private:
  void add(Local& l, const double* vj, const Neighbour<D>& nb) const {
    const double w = l.m[nb.j] / l.rho[nb.j] * nb.F;
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) l.k(a, b) += w * (vj[a] - l.vi[a]) * nb.rij[b];
    if (renormalised_) l.M.noalias() -= w * nb.rij * nb.rij.transpose();
  }
  bool renormalised_ = false;
  ImplicitPart implicit_ = ImplicitPart::none;
  Field* kappa_ = nullptr;
  const Field* wall_velocity_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeVelocityGradient, VelocityGradient)
}  // namespace vesph
