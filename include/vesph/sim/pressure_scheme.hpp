#pragma once
// Pressure schemes as plug-ins (docs/architecture.md "Pressure schemes"): `[solver] scheme`
// names one of the registry (src/sim/pressure_schemes.cpp). A scheme owns what differs between
// them: its validation of the scene (what it refuses, with the fix in the message), the step
// hooks it adds (the ISPH projection), the default CFL coefficient of the integrator's acoustic
// limit, and the default speed guard of the run's checks (checks.max_speed). The weakly
// compressible scheme takes its pressure from an effect (equation_of_state) and adds no hook.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/boundary/registry.hpp"
#include "vesph/io/config.hpp"
#include "vesph/physics/effect.hpp"
#include "vesph/physics/step_hook.hpp"
#include "vesph/sim/system.hpp"

namespace vesph {

// What a scheme checks and extends while the scene is built (after the boundaries and effects,
// before the system's setup).
template <int D>
struct SchemeBuild {
  const std::string& file;  // the scene file, for messages
  ConfigTable& solver;      // [solver]
  const std::vector<WallPoint<D>>& wall_points;
  const BoundaryFacts& boundaries;
  const std::vector<std::unique_ptr<Effect<D>>>& effects;
  std::vector<std::unique_ptr<StepHook<D>>>& hooks;  // the scheme's hooks run before the boundaries'
};

template <int D>
class PressureScheme {
 public:
  virtual ~PressureScheme() = default;
  virtual std::string_view name() const = 0;
  // Validates the scene for this scheme (InputError) and adds its hooks.
  virtual void build(SchemeBuild<D>& scene) const = 0;
  // The integrator's CFL coefficient when the scene gives none (integrator.cfl).
  virtual double defaultCfl() const = 0;
  // checks.max_speed when the scene gives none, m/s; velocity_scale: the scene's speed scale
  // (the default tolerances' reference velocity).
  virtual double defaultSpeedGuard(const SphSystem<D>& system, double velocity_scale) const = 0;
};

template <int D>
struct SchemeEntry {
  std::string name;
  std::string summary;
  std::unique_ptr<PressureScheme<D>> (*make)();
};

template <int D>
const std::vector<SchemeEntry<D>>& pressureSchemeRegistry();

// Reads solver.scheme and builds that scheme.
template <int D>
std::unique_ptr<PressureScheme<D>> makePressureScheme(ConfigTable& solver);

// The speed guard of a scene without a sound speed: 1000 times the flow's speed scale, the
// larger of velocity_scale and the free-fall speed sqrt(|g| L) over the domain's largest extent
// L: a run that has blown up stops there, before the step size has collapsed and the last good
// state is itself far from any flow; 1e30 when the scene gives no scale.
template <int D>
double flowSpeedGuard(const SphSystem<D>& system, double velocity_scale);

}  // namespace vesph
