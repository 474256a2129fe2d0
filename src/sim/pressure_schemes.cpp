#include <algorithm>
#include <cmath>

#include "vesph/sim/pressure_scheme.hpp"

namespace vesph {

// One line per pressure scheme: name in scenes ([solver] scheme), factory (defined in the
// scheme's own file), summary. The first is the default.
#define VESPH_PRESSURE_SCHEMES(X)                                                                       \
  X(wcsph, makeWcsphScheme, "weakly compressible: the pressure from an equation of state (an effect), thesis 3.5") \
  X(isph, makeIsphScheme, "incompressible: the pressure projection after every step, thesis §3.5 (src/isph)")

#define VESPH_DECLARE(NAME, FN, SUMMARY) \
  template <int D>                       \
  std::unique_ptr<PressureScheme<D>> FN();
VESPH_PRESSURE_SCHEMES(VESPH_DECLARE)

template <int D>
const std::vector<SchemeEntry<D>>& pressureSchemeRegistry() {
#define VESPH_ENTRY(NAME, FN, SUMMARY) SchemeEntry<D>{#NAME, SUMMARY, &FN<D>},
  static const std::vector<SchemeEntry<D>> registry = {VESPH_PRESSURE_SCHEMES(VESPH_ENTRY)};
  return registry;
}

template <int D>
std::unique_ptr<PressureScheme<D>> makePressureScheme(ConfigTable& solver) {
  std::vector<std::string> names;
  for (const auto& e : pressureSchemeRegistry<D>()) names.push_back(e.name);
  const std::string name = solver.choice("scheme", names.front(), names);
  for (const auto& e : pressureSchemeRegistry<D>())
    if (e.name == name) return e.make();
  solver.fail("scheme", "a known pressure scheme");
}

template <int D>
double flowSpeedGuard(const SphSystem<D>& system, double velocity_scale) {
  double extent = 0;
  for (int a = 0; a < D; ++a) extent = std::max(extent, system.domain.length(a));
  const double speed = std::max(velocity_scale, std::sqrt(system.bodyAcceleration().norm() * extent));
  return speed > 0 ? 1e3 * speed : 1e30;
}

template const std::vector<SchemeEntry<2>>& pressureSchemeRegistry<2>();
template const std::vector<SchemeEntry<3>>& pressureSchemeRegistry<3>();
template std::unique_ptr<PressureScheme<2>> makePressureScheme<2>(ConfigTable&);
template std::unique_ptr<PressureScheme<3>> makePressureScheme<3>(ConfigTable&);
template double flowSpeedGuard<2>(const SphSystem<2>&, double);
template double flowSpeedGuard<3>(const SphSystem<3>&, double);

}  // namespace vesph
