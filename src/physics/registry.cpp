#include "vesph/physics/registry.hpp"

#include <algorithm>

namespace vesph {

// One line per effect: name in scenes, factory (defined in the effect's own file), summary.
#define VESPH_EFFECTS(X)                                                                        \
  X(continuity, makeContinuity, "density rate, Fang et al. eq. (26)")                          \
  X(equation_of_state, makeEquationOfState, "WCSPH pressure p = p0 + c^2 (rho - rho0), thesis 3.5") \
  X(pressure_gradient, makePressureGradient, "-grad(p)/rho, thesis eq. (3.18) or (3.17)")        \
  X(viscosity, makeViscosity, "Newtonian viscous force by the SPH Laplacian, thesis eq. (3.37) (form: laplacian, or stress for a stress-free free surface)") \
  X(body_force, makeBodyForce, "constant body acceleration (driving force, gravity)")                \
  X(velocity_gradient, makeVelocityGradient, "velocity gradient kappa, Fang et al. eq. (23)")       \
  X(stress_divergence, makeStressDivergence, "elastic stress force div(S)/rho, Fang et al. eq. (27)") \
  X(oldroyd_b, makeOldroydB, "Oldroyd-B elastic stress, Fang et al. eq. (28) (relaxation_time, polymer_viscosity)") \
  X(ucm, makeUcm, "upper-convected Maxwell: Oldroyd-B without solvent viscosity")                  \
  X(second_order_fluid, makeSecondOrderFluid, "second-order fluid, thesis eqs. (2.2)/(2.3), Table 2-1 (alpha1, alpha2, form, derivative, procedure)") \
  X(xpp, makeXpp, "single-equation eXtended Pom-Pom, Verbeeten et al. 2001 (backbone_relaxation_time, modulus, arms, ...)") \
  X(artificial_viscosity, makeArtificialViscosity, "Monaghan artificial viscosity, Fang et al. eqs. (30)-(37) (alpha, beta)") \
  X(xsph, makeXsph, "XSPH particle movement, thesis 3.6 (epsilon, form)")                         \
  X(density_diffusion, makeDensityDiffusion, "delta-SPH density diffusion, Molteni & Colagrossi 2009 or Antuono et al. 2010 (delta, hydrostatic, walls, form)") \
  X(artificial_stress, makeArtificialStress, "artificial stress against the tensile instability, Fang et al. eqs. (38)-(44) (epsilon, exponent)") \
  X(particle_shifting, makeParticleShifting, "Fickian particle shifting as a velocity, Lind et al. 2012, Skillen et al. 2013 (coefficient, speed)") \
  X(free_surface, makeFreeSurface, "free-surface particles: number density n_i <= threshold n_ref (thesis §4.2) or Marrone et al. 2010 (method = \"marrone\")") \
  X(surface_pressure, makeSurfacePressure, "WCSPH free-surface pressure p = n.T.n on the flagged particles, thesis §4.2 sigma.n = 0 (value, ambient_pressure)")

#define VESPH_DECLARE(NAME, FN, SUMMARY) \
  template <int D>                       \
  std::unique_ptr<Effect<D>> FN(ConfigTable&);
VESPH_EFFECTS(VESPH_DECLARE)

template <int D>
const std::vector<EffectEntry<D>>& effectRegistry() {
#define VESPH_ENTRY(NAME, FN, SUMMARY) EffectEntry<D>{#NAME, SUMMARY, &FN<D>},
  static const std::vector<EffectEntry<D>> registry = {VESPH_EFFECTS(VESPH_ENTRY)};
  return registry;
}

template <int D>
std::vector<std::unique_ptr<Effect<D>>> makeEffects(ConfigTable& effects_table) {
  std::vector<std::unique_ptr<Effect<D>>> out;
  // One constitutive model per scene: each evolves the elastic stress (and writes the extra
  // stress) as the only model, so a second would silently overwrite the first one's rate.
  static const std::vector<std::string> kConstitutiveModels = {"oldroyd_b", "ucm", "second_order_fluid", "xpp"};
  std::string first_model;
  for (const std::string& name : effects_table.keys()) {
    if (std::find(kConstitutiveModels.begin(), kConstitutiveModels.end(), name) == kConstitutiveModels.end()) continue;
    if (!first_model.empty())
      effects_table.fail(name, "one constitutive model per scene, but the scene has both [" +
                                   effects_table.keyPath(first_model) + "] and [" + effects_table.keyPath(name) +
                                   "]: remove one");
    first_model = name;
  }
  for (const std::string& name : effects_table.keys()) {
    const EffectEntry<D>* entry = nullptr;
    for (const auto& e : effectRegistry<D>())
      if (e.name == name) entry = &e;
    if (!entry) {
      std::string valid;
      for (const auto& e : effectRegistry<D>()) valid += (valid.empty() ? "" : ", ") + e.name;
      effects_table.fail(name, "the name of an effect (" + valid + ")");
    }
    if (!effects_table.isTable(name))
      effects_table.fail(name, "a table: write [" + effects_table.keyPath(name) + "]");
    ConfigTable sub = effects_table.table(name);
    out.push_back(entry->make(sub));
  }
  return out;
}

template const std::vector<EffectEntry<2>>& effectRegistry<2>();
template const std::vector<EffectEntry<3>>& effectRegistry<3>();
template std::vector<std::unique_ptr<Effect<2>>> makeEffects<2>(ConfigTable&);
template std::vector<std::unique_ptr<Effect<3>>> makeEffects<3>(ConfigTable&);

}  // namespace vesph
