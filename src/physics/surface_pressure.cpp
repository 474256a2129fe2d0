// The normal part of the dynamic free-surface condition for weakly compressible SPH.
//
// On a free surface without surface tension the traction of the total stress vanishes,
// sigma . n = 0 with sigma = -p I + T (thesis §4.2, the jump condition of the momentum balance
// with a passive ambient). Its normal part fixes the pressure at the surface:
//   p_s = p_ambient + n . T . n
// (T the extra stress: the field "extra_stress", solvent and polymer parts, of the scene's
// constitutive model). The ISPH projection imposes p = 0 on its flagged particles as a
// Dirichlet value; in WCSPH the equation of state gives the surface particles whatever
// pressure their density has, and in an extending surface (a die's lip, where the outer rows
// accelerate from the wall's rest to the jet's speed) that is a tension of tens of kPa which
// nothing in the fluid's law balances (docs/studies.md §5, "Where the two schemes part").
// This effect replaces, for every particle the free-surface detection flags, the equation of
// state's pressure by p_s before the forces are taken: the pressure gradient then sees the
// surface condition, as the ISPH projection's Dirichlet rows do. The density is left as the
// continuity equation evolves it; only the pressure the forces read changes.
// The wall particles' pressure is extrapolated from the fluid before this phase (the walls run
// after the state phase), so walls beside a flagged particle see its equation-of-state value.
//
//   value = "normal_stress"  p_s = p_ambient + n.T.n: T the field "extra_stress" where a model
//                            writes it (the second-order fluid); otherwise the viscous stress
//                            mu (kappa + kappa^T) of [effects.velocity_gradient] plus the
//                            "elastic_stress" of a rate-type model where there is one (a
//                            Newtonian fluid, Oldroyd-B, UCM, XPP). The viscous part belongs
//                            with [effects.viscosity] form = "stress", whose truncated sums at
//                            the surface leave the traction -tau.n that p_s n then balances
//                            (docs/theory.md §5.4); Morris' Laplacian leaves mu dv/dn instead.
//   value = "zero"           p_s = p_ambient (the Newtonian-inviscid approximation of ISPH)
// n is the free-surface detection's outward normal (field "surface_normal",
// src/physics/free_surface.cpp); a flagged particle without a normal (a lone particle, a
// symmetric neighbourhood) gets p_ambient.
#include "vesph/physics/constitutive.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class SurfacePressure final : public Effect<D> {
 public:
  explicit SurfacePressure(ConfigTable& cfg) {
    normal_stress_ = cfg.choice("value", "normal_stress", {"normal_stress", "zero"}) == "normal_stress";
    ambient_ = cfg.number("ambient_pressure", 0.0, Bound::any, "Pa");
  }
  std::string_view name() const override { return "surface_pressure"; }
  // After the pair pass that flags the surface (and after the second-order fluid's stress,
  // written in that pass) and after the rate-type models, which write the extra stress in
  // this phase.
  Phase phase() const override { return Phase::rates; }
  int passOrder() const override { return 100; }

  void setup(Setup<D>& s) override {
    const std::string me = "effects.surface_pressure";
    if (!s.find("equation_of_state"))
      throw InputError(me + " sets the weakly compressible pressure of the surface particles and needs "
                       "[effects.equation_of_state]; the ISPH projection imposes its surface pressure itself "
                       "(solver.scheme = \"isph\")");
    if (!s.find("free_surface"))
      throw InputError(me + " needs the free-surface flags and normals: add [effects.free_surface]");
    pressure_ = s.particles.fields.find("pressure");
    flag_ = s.particles.fields.find("free_surface");
    normal_ = s.particles.fields.find("surface_normal");
    if (!pressure_ || !flag_ || !normal_) throw std::logic_error("surface_pressure: fields missing after setup");
    if (normal_stress_) {
      kinematic_viscosity_ = s.viscosity / s.rest_density;  // T holds the viscous stress either way
      extra_ = s.particles.fields.find("extra_stress");
      if (!extra_) {
        kappa_ = s.particles.fields.find("velocity_gradient");
        if (!kappa_)
          throw InputError(me + ".value = \"normal_stress\" needs the stress T: the extra stress of the "
                           "second-order fluid, or the velocity gradient ([effects.velocity_gradient]) for the "
                           "viscous stress mu (kappa + kappa^T); or set value = \"zero\"");
        viscosity_ = s.viscosity;
        elastic_ = s.particles.fields.find("elastic_stress");
        elastic_full_ = elastic_ && elastic_->components == D * D;
      }
    }
  }

  // p_s = 2 mu n.kappa.n is a viscous stress applied explicitly through the pressure: its step
  // limit is the viscous one, also where an implicit-explicit integrator takes [effects.viscosity]
  // implicitly (docs/theory.md §10 "The normal-stress surface").
  void stability(StabilityInputs& in) const override {
    in.kinematic_viscosity = std::max(in.kinematic_viscosity, kinematic_viscosity_);
  }

  void particles(const RhsContext<D>&, std::size_t begin, std::size_t end) const override {
    const double* flag = flag_->data.data();
    const double* normal = normal_->data.data();
    double* p = pressure_->data.data();
    constexpr int nc = symmetricComponents<D>();
    for (std::size_t i = begin; i < end; ++i) {
      if (!(flag[i] > 0.5)) continue;
      double value = ambient_;
      if (normal_stress_) {
        const Eigen::Map<const Vec<D>> n(normal + D * i);
        if (extra_) {
          value += n.dot(unpackSymmetric<D>(extra_->data.data() + nc * i) * n);
        } else {
          // n.(kappa + kappa^T).n = 2 n.kappa.n (kappa row-major, as the full stress); n.S.n =
          // n.sym(S).n for the second-order fluid's full tensor too
          value += 2.0 * viscosity_ * n.dot(loadStress<D>(kappa_->data.data(), true, i) * n);
          if (elastic_) value += n.dot(loadStress<D>(elastic_->data.data(), elastic_full_, i) * n);
        }
      }
      p[i] = value;
    }
  }

 private:
  bool normal_stress_ = true;
  double ambient_ = 0;
  double kinematic_viscosity_ = 0;  // mu/rho0 when p_s carries the viscous stress, else 0
  Field* pressure_ = nullptr;
  const Field* flag_ = nullptr;
  const Field* normal_ = nullptr;
  const Field* extra_ = nullptr;
  // Without an extra stress field: the viscous stress from the velocity gradient, plus a
  // rate-type model's elastic stress where there is one.
  const Field* kappa_ = nullptr;
  const Field* elastic_ = nullptr;
  bool elastic_full_ = false;  // the second-order fluid's full tensor (else packed symmetric)
  double viscosity_ = 0;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeSurfacePressure, SurfacePressure)
}  // namespace vesph
