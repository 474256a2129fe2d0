#include "vesph/time/integrator.hpp"
#include "vesph/time/integrator_factory.hpp"

#include <algorithm>
#include <cmath>

namespace vesph {

double StepLimits::smallest() const { return std::min({acoustic, viscous, force, relaxation}); }

StepLimits stepLimits(const StabilitySnapshot& s, const StepControl& c) {
  StepLimits l;
  const double signal = s.sound_speed + s.elastic_wave_speed + s.max_speed;
  if (signal > 0) l.acoustic = c.cfl * s.h / signal;
  if (s.kinematic_viscosity > 0) l.viscous = c.viscous_coefficient * s.h * s.h / s.kinematic_viscosity;
  if (s.max_acceleration > 0) l.force = c.force_coefficient * std::sqrt(s.h / s.max_acceleration);
  if (s.relaxation_time > 0) l.relaxation = c.relaxation_coefficient * s.relaxation_time;
  l.acoustic = std::min(l.acoustic, c.max_step);  // max_step (default none) caps every step
  return l;
}

std::unique_ptr<Integrator> makeLeapfrog(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeMidpoint(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeArkode(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeArkodeFixed(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeSymplectic(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeArkodeImex(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeArkodeImexFixed(ConfigTable&, const StepControl&, const ReferenceScales&);
std::unique_ptr<Integrator> makeSemiImplicit(ConfigTable&, const StepControl&, const ReferenceScales&);

const std::vector<IntegratorEntry>& integratorRegistry() {
  static const std::vector<IntegratorEntry> registry = {
      {"leapfrog", "leapfrog predictor-corrector of the thesis, eq. (3.39) ff.; fixed step from the stability limits; 2nd order", &makeLeapfrog},
      {"midpoint", "midpoint predictor-corrector of Fang et al., eqs. (49)-(50); fixed step from the stability limits; 2nd order", &makeMidpoint},
      {"arkode", "SUNDIALS ARKODE ERKStep, adaptive error-controlled explicit Runge-Kutta (integrator.table, rtol, atol_*), step also bounded by the stability limits", &makeArkode, true},
      {"arkode-fixed", "SUNDIALS ARKODE ERKStep in fixed-step mode (integrator.table); step from the stability limits or integrator.step", &makeArkodeFixed},
      {"symplectic", "symplectic position Verlet (drift-kick-drift), one evaluation per step (the last midpoint rates predict the next midpoint); fixed step from the stability limits; 2nd order", &makeSymplectic, false, kSymplecticWcsphDefaultCfl},
      {"arkode-imex", "SUNDIALS ARKODE ARKStep, adaptive error-controlled implicit-explicit Runge-Kutta (integrator.table: ARK324L2SA ...); viscous force and Oldroyd-B/UCM relaxation implicit (Newton, matrix-free GMRES), step bounded by the explicit part's limits only", &makeArkodeImex, true},
      {"arkode-imex-fixed", "SUNDIALS ARKODE ARKStep implicit-explicit in fixed-step mode (integrator.table); step from the explicit part's limits or integrator.step", &makeArkodeImexFixed},
      {"semi-implicit", "Strang splitting of arkode-imex's f_E + f_I: half an L-stable SDIRK step of the implicit part (matrix-free GMRES, integrator.rtol), a midpoint step of the explicit part, half an implicit step; fixed step from the explicit part's limits or integrator.step; 2nd order", &makeSemiImplicit},
  };
  return registry;
}

std::unique_ptr<Integrator> makeIntegrator(ConfigTable& cfg, const ReferenceScales& scales, double default_cfl) {
  std::vector<std::string> names;
  for (const auto& e : integratorRegistry()) names.push_back(e.name);
  const std::string type = cfg.choice("type", "leapfrog", names);
  const IntegratorEntry* entry = nullptr;
  for (const auto& e : integratorRegistry())
    if (e.name == type) entry = &e;
  if (!entry) cfg.fail("type", "a known integrator");
  // The WCSPH scheme passes the constant kWcsphDefaultCfl itself; an integrator with a stability
  // range of its own (the one-evaluation symplectic scheme) replaces it. ISPH keeps its 0.175.
  if (entry->wcsph_default_cfl > 0 && default_cfl == kWcsphDefaultCfl) default_cfl = entry->wcsph_default_cfl;
  StepControl c;  // its members hold the defaults (also printed by `vesph list --json`)
  // The fixed-step integrators take the limits as their step, so the coefficients stay in
  // their explicit stability range. For the adaptive 'arkode' the limits only cap a step that
  // the error control chooses (and rejects when it is unstable); a cap above the fixed-step
  // range lets the controller take the step it finds (docs/validation.md §10: in the drop
  // impact the acoustic cap, not the error, bounded DP5's step).
  const double cap_range = entry->adaptive ? 10.0 : 1.0;
  c.cfl = cfg.numberIn("cfl", default_cfl, 1e-6, cap_range);
  c.viscous_coefficient = cfg.numberIn("viscous_coefficient", c.viscous_coefficient, 1e-6, cap_range);
  c.force_coefficient = cfg.numberIn("force_coefficient", c.force_coefficient, 1e-6, 1.0);
  // The symplectic scheme's relaxation is stable to dt = lambda (src/time/symplectic.cpp), the
  // two-evaluation schemes' to 2 lambda.
  c.relaxation_coefficient =
      cfg.numberIn("relaxation_coefficient", c.relaxation_coefficient, 1e-6, type == "symplectic" ? 1.0 : 2.0);
  c.max_step = cfg.optionalNumber("max_step", Bound::positive, "s").value_or(c.max_step);
  c.fixed_step = cfg.optionalNumber("step", Bound::positive, "s").value_or(0.0);
  if (c.fixed_step > 0 && entry->adaptive)
    cfg.fail("step", "no fixed step for the adaptive integrator '" + type + "' (use '" + type + "-fixed', or initial_step)");
  return entry->make(cfg, c, scales);
}

}  // namespace vesph
