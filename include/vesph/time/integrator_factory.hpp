#pragma once
// The integrators by name, built from the scene's [integrator] table (the config-reading side
// of vesph/time/integrator.hpp, which itself knows nothing of the configuration).
#include <memory>
#include <string>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

struct IntegratorEntry {
  std::string name;
  std::string summary;
  std::unique_ptr<Integrator> (*make)(ConfigTable& cfg, const StepControl& control, const ReferenceScales& scales);
  // Error-controlled step (the stability limits only cap it): no integrator.step, and the
  // limit coefficients may exceed the fixed-step range.
  bool adaptive = false;
  // The integrator's own default CFL coefficient under WCSPH, when its stability range differs
  // from the predictor-correctors' (0: the pressure scheme's default, kWcsphDefaultCfl).
  double wcsph_default_cfl = 0;
};
const std::vector<IntegratorEntry>& integratorRegistry();

// Reads [integrator] (type and the step-control keys) and builds the integrator. default_cfl:
// the pressure scheme's CFL coefficient when the scene gives none (WCSPH 0.125; ISPH 0.175,
// thesis §3.5); under WCSPH an integrator with its own wcsph_default_cfl takes that instead.
std::unique_ptr<Integrator> makeIntegrator(ConfigTable& cfg, const ReferenceScales& scales, double default_cfl = kWcsphDefaultCfl);

}  // namespace vesph
