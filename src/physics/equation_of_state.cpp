// Weakly compressible equation of state (thesis 3.5):  p = p0 + c^2 (rho - rho0).
//
// The sound speed c is either given (m/s) or chosen by the rule of thesis eq. (3.38)
// (Morris et al. 1997):
//   c^2 = phi * max( V^2/delta, nu V/(L delta), |F| L/delta )
// with V the expected maximum speed, L a characteristic length, F the body acceleration of
// the scene, nu = mu/rho0 and delta the admissible relative density variation.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class EquationOfState final : public Effect<D>, public PressureModel {
 public:
  explicit EquationOfState(ConfigTable& cfg) {
    // |p0| <= 1e12 Pa (a thousand times the pressure at the bottom of the deepest ocean): 1e308
    // overflowed the pressure of the first evaluation.
    p0_ = cfg.numberIn("reference_pressure", 0.0, -1e12, 1e12, "Pa");
    if (cfg.isTable("sound_speed")) {
      ConfigTable rule = cfg.table("sound_speed");
      phi_ = rule.number("phi", 4.0, Bound::positive);
      delta_ = rule.numberIn("delta", 0.01, 1e-8, 0.5);
      velocity_ = rule.number("velocity", std::nullopt, Bound::nonnegative, "m/s");
      length_ = rule.number("length", std::nullopt, Bound::positive, "m");
      from_rule_ = true;
    } else {
      if (!cfg.has("sound_speed"))
        cfg.fail("sound_speed", "a sound speed in m/s, or the rule of thesis eq. (3.38) as "
                                "{ phi = 4.0, delta = 0.01, velocity = V, length = L }");
      c_ = cfg.number("sound_speed", std::nullopt, Bound::positive, "m/s");
    }
  }

  std::string_view name() const override { return "equation_of_state"; }
  Phase phase() const override { return Phase::state; }
  const PressureModel* pressureModel() const override { return this; }

  void setup(Setup<D>& s) override {
    rho0_ = s.rest_density;
    if (from_rule_) {
      const double nu = s.viscosity / s.rest_density, F = s.body_acceleration.norm();
      const double c2 = phi_ * std::max({velocity_ * velocity_ / delta_,
                                         nu * velocity_ / (length_ * delta_), F * length_ / delta_});
      if (!(c2 > 0))
        throw InputError("effects.equation_of_state.sound_speed: the rule of eq. (3.38) gives zero "
                         "(velocity, viscosity and body force are all zero); give sound_speed in m/s");
      c_ = std::sqrt(c2);
    }
    pressure_ = &s.particles.fields.require("pressure", 1);
  }

  void stability(StabilityInputs& in) const override { in.sound_speed = std::max(in.sound_speed, c_); }

  void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    const double* rho = ctx.particles.density.data();
    double* p = pressure_->data.data();
    for (std::size_t i = begin; i < end; ++i) p[i] = pressure(rho[i]);
  }

  double pressure(double rho) const override { return p0_ + c_ * c_ * (rho - rho0_); }
  double densityFor(double p) const override { return rho0_ + (p - p0_) / (c_ * c_); }
  double soundSpeed() const override { return c_; }
  double designDensityVariation() const override { return from_rule_ ? delta_ : 0.0; }
  double designVelocity() const override { return from_rule_ ? velocity_ : 0.0; }
  double designLength() const override { return from_rule_ ? length_ : 0.0; }

 private:
  double p0_ = 0, c_ = 0, rho0_ = 1;
  bool from_rule_ = false;
  double phi_ = 4, delta_ = 0.01, velocity_ = 0, length_ = 1;
  Field* pressure_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeEquationOfState, EquationOfState)
}  // namespace vesph
