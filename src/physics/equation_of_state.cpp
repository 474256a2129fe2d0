// Weakly compressible equation of state (thesis 3.5, docs/theory.md "Equation of state"):
//   form = "linear" (default):  p = p0 + c^2 (rho - rho0)
//   form = "tait":              p = p0 + B ((rho/rho0)^gamma - 1),  B = c^2 rho0 / gamma
// (Tait's equation as Monaghan 1994, J. Comput. Phys. 110:399, eq. 3.3 uses it for water after
// Batchelor 1967 §1.7: gamma = 7; its sound speed at rho0 is c, which sets the step limits).
//
// The sound speed c is either given (m/s) or chosen by a rule:
//  - thesis eq. (3.38) (Morris et al. 1997):
//      c^2 = phi * max( V^2/delta, nu V/(L delta), |F| L/delta )
//    with V the expected maximum speed, L a characteristic length, F the body acceleration of
//    the scene, nu = mu/rho0 and delta the admissible relative density variation;
//  - the free-surface rule of DualSPHysics and PySPH (Monaghan 1994 §3):
//      c = coefsound sqrt(|g| H)
//    with g the scene's body acceleration and H the water depth: eq. (3.38)'s first term with
//    V = sqrt(|g| H), delta = 1/coefsound^2 and phi = 1, which are reported as its design values.
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
    // form and gamma are read only when present: the resolved scene of a linear scene stays as
    // it was (it is stored in the output and compared on --resume).
    if (cfg.has("form")) tait_ = cfg.choice("form", "linear", {"linear", "tait"}) == "tait";
    if (cfg.has("gamma")) {
      if (!tait_) cfg.fail("gamma", "no gamma with form = \"linear\" (the exponent of form = \"tait\")");
      gamma_ = cfg.numberIn("gamma", 7.0, 1.0, 20.0);
    }
    if (cfg.isTable("sound_speed") && cfg.table("sound_speed").has("coefsound")) {
      ConfigTable rule = cfg.table("sound_speed");
      // DualSPHysics' coefsound is 10-40 (its default 20); below 1 the flow would be supersonic.
      coefsound_ = rule.numberIn("coefsound", std::nullopt, 1.0, 1000.0);
      length_ = rule.number("height", std::nullopt, Bound::positive, "m");
      for (const char* key : {"phi", "delta", "velocity", "length"})
        if (rule.has(key))
          rule.fail(key, "no " + std::string(key) + " with coefsound (the rule c = coefsound sqrt(|g| height))");
      from_rule_ = true;
    } else if (cfg.isTable("sound_speed")) {
      ConfigTable rule = cfg.table("sound_speed");
      phi_ = rule.number("phi", 4.0, Bound::positive);
      delta_ = rule.numberIn("delta", 0.01, 1e-8, 0.5);
      velocity_ = rule.number("velocity", std::nullopt, Bound::nonnegative, "m/s");
      length_ = rule.number("length", std::nullopt, Bound::positive, "m");
      from_rule_ = true;
    } else {
      if (!cfg.has("sound_speed"))
        cfg.fail("sound_speed", "a sound speed in m/s, or the rule of thesis eq. (3.38) as "
                                "{ phi = 4.0, delta = 0.01, velocity = V, length = L }, or "
                                "{ coefsound = 20, height = H } for c = coefsound sqrt(|g| H)");
      c_ = cfg.number("sound_speed", std::nullopt, Bound::positive, "m/s");
    }
  }

  std::string_view name() const override { return "equation_of_state"; }
  Phase phase() const override { return Phase::state; }
  const PressureModel* pressureModel() const override { return this; }

  void setup(Setup<D>& s) override {
    rho0_ = s.rest_density;
    if (coefsound_ > 0) {
      const double g = s.body_acceleration.norm();
      if (!(g > 0))
        throw InputError("effects.equation_of_state.sound_speed.coefsound: the rule c = coefsound sqrt(|g| H) needs "
                         "a body acceleration (add [effects.body_force]); give sound_speed in m/s otherwise");
      velocity_ = std::sqrt(g * length_);
      delta_ = 1.0 / (coefsound_ * coefsound_);
      c_ = coefsound_ * velocity_;
    } else if (from_rule_) {
      const double nu = s.viscosity / s.rest_density, F = s.body_acceleration.norm();
      const double c2 = phi_ * std::max({velocity_ * velocity_ / delta_,
                                         nu * velocity_ / (length_ * delta_), F * length_ / delta_});
      if (!(c2 > 0))
        throw InputError("effects.equation_of_state.sound_speed: the rule of eq. (3.38) gives zero "
                         "(velocity, viscosity and body force are all zero); give sound_speed in m/s");
      c_ = std::sqrt(c2);
    }
    tait_b_ = c_ * c_ * rho0_ / gamma_;
    whole_gamma_ = gamma_ == std::round(gamma_) ? static_cast<int>(gamma_) : 0;
    pressure_ = &s.particles.fields.require("pressure", 1);
  }

  void stability(StabilityInputs& in) const override { in.sound_speed = std::max(in.sound_speed, c_); }

  void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    const double* rho = ctx.particles.density.data();
    double* p = pressure_->data.data();
    if (tait_) {
      for (std::size_t i = begin; i < end; ++i) p[i] = taitPressure(rho[i]);
    } else {
      for (std::size_t i = begin; i < end; ++i) p[i] = p0_ + c_ * c_ * (rho[i] - rho0_);
    }
  }

  double pressure(double rho) const override {
    if (tait_) return taitPressure(rho);
    return p0_ + c_ * c_ * (rho - rho0_);
  }
  // The inverse (walls' densities from their extrapolated pressure, a hydrostatic start). Tait's
  // pressure is bounded below by p0 - B (rho -> 0): a pressure below it (an extrapolation at a
  // wall near the free surface) is given the density of p0 - B (1 - kTaitFloor), whose ratio
  // kTaitFloor^(1/gamma) (0.14 for gamma = 7) keeps the density positive.
  double densityFor(double p) const override {
    if (tait_) return rho0_ * std::pow(std::max(1.0 + (p - p0_) / tait_b_, kTaitFloor), 1.0 / gamma_);
    return rho0_ + (p - p0_) / (c_ * c_);
  }
  double soundSpeed() const override { return c_; }

  // (rho/rho0)^gamma by multiplications for a whole gamma (7 for water: 4 products, several
  // times cheaper than std::pow in the state phase of every right-hand side), else std::pow.
  double taitPressure(double rho) const {
    const double r = rho / rho0_;
    double power = 1.0;
    if (whole_gamma_ > 0) {
      double base = r;
      for (int e = whole_gamma_; e > 0; e >>= 1) {
        if (e & 1) power *= base;
        base *= base;
      }
    } else {
      power = std::pow(r, gamma_);
    }
    return p0_ + tait_b_ * (power - 1.0);
  }
  double designDensityVariation() const override { return from_rule_ ? delta_ : 0.0; }
  double designVelocity() const override { return from_rule_ ? velocity_ : 0.0; }
  double designLength() const override { return from_rule_ ? length_ : 0.0; }

 private:
  static constexpr double kTaitFloor = 1e-6;
  double p0_ = 0, c_ = 0, rho0_ = 1;
  bool tait_ = false;
  double gamma_ = 7.0, tait_b_ = 0;
  int whole_gamma_ = 7;  // gamma when it is a whole number, else 0
  double coefsound_ = 0;  // > 0: c = coefsound sqrt(|g| H), H in length_
  bool from_rule_ = false;
  double phi_ = 4, delta_ = 0.01, velocity_ = 0, length_ = 1;
  Field* pressure_ = nullptr;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeEquationOfState, EquationOfState)
}  // namespace vesph
