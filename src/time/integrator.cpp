#include "vesph/time/integrator.hpp"

#include <algorithm>
#include <cmath>

namespace vesph {

double StepLimits::smallest() const { return std::min({acoustic, viscous, force}); }

StepLimits stepLimits(const StabilitySnapshot& s, const StepControl& c) {
  StepLimits l;
  const double signal = s.sound_speed + s.max_speed;
  if (signal > 0) l.acoustic = c.cfl * s.h / signal;
  if (s.kinematic_viscosity > 0) l.viscous = c.viscous_coefficient * s.h * s.h / s.kinematic_viscosity;
  if (s.max_acceleration > 0) l.force = c.force_coefficient * std::sqrt(s.h / s.max_acceleration);
  l.acoustic = std::min(l.acoustic, c.max_step);  // max_step (default none) caps every step
  return l;
}

std::unique_ptr<Integrator> makeLeapfrog(ConfigTable& cfg, const StepControl& control);
std::unique_ptr<Integrator> makeMidpoint(ConfigTable& cfg, const StepControl& control);

const std::vector<IntegratorEntry>& integratorRegistry() {
  static const std::vector<IntegratorEntry> registry = {
      {"leapfrog", "leapfrog predictor-corrector of the thesis, eq. (3.39) ff.; fixed step from the stability limits; 2nd order", &makeLeapfrog},
      {"midpoint", "midpoint predictor-corrector of Fang et al., eqs. (49)-(50); fixed step from the stability limits; 2nd order", &makeMidpoint},
  };
  return registry;
}

std::unique_ptr<Integrator> makeIntegrator(ConfigTable& cfg) {
  std::vector<std::string> names;
  for (const auto& e : integratorRegistry()) names.push_back(e.name);
  const std::string type = cfg.choice("type", "leapfrog", names);
  StepControl c;
  c.cfl = cfg.numberIn("cfl", 0.125, 1e-6, 1.0);
  c.viscous_coefficient = cfg.numberIn("viscous_coefficient", 0.125, 1e-6, 1.0);
  c.force_coefficient = cfg.numberIn("force_coefficient", 0.25, 1e-6, 1.0);
  if (cfg.has("max_step")) c.max_step = cfg.number("max_step", std::nullopt, Bound::positive, "s");
  else cfg.markRead("max_step");
  for (const auto& e : integratorRegistry())
    if (e.name == type) return e.make(cfg, c);
  cfg.fail("type", "a known integrator");
}

}  // namespace vesph
