// Dummy walls (src/boundary/dummy_walls.cpp, docs/theory.md §6): the pressure floor of a wall
// block, per block, and its input checks.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "vesph/sim/simulation.hpp"
#include "vesph/sim/system.hpp"

using namespace vesph;

namespace {

const char* kDie = VESPH_SOURCE_DIR "/cases/die_swell_newtonian.toml";

// The die with its fluid put in tension (density 1 % below rho0) and one right-hand side
// evaluated: the walls' extrapolated pressures. Returns {lowest, highest} pressure over the
// wall particles (kinds wall and dummy) below the die (y < 0) and above it (y > W).
struct WallPressures {
  double lower_min = 1e300, lower_max = -1e300, upper_min = 1e300, upper_max = -1e300;
  double fluid_p = 0;      // the fluid's pressure (equation of state at 0.99 rho0)
  double lower_rho_max = 0;
};

WallPressures stretchedDie(const std::vector<std::string>& overrides) {
  SceneHeader h;
  Config cfg = loadScene(kDie, overrides, h);
  Simulation<2> sim(cfg, h);
  SphSystem<2>& sys = sim.system();
  ParticleSet<2>& P = sys.particles;
  const std::size_t n = P.n_moving;
  std::vector<double> y = sim.state(), ydot(y.size());
  const double rho0 = 1000.0;
  for (std::size_t i = 0; i < n; ++i) y[2 * n + i] = 0.99 * rho0;  // state: positions, densities, velocities
  sys.evaluate(0.0, y.data(), ydot.data());
  const Field* p = P.fields.find("pressure");
  REQUIRE(p != nullptr);
  WallPressures out;
  out.fluid_p = p->data[0];
  for (std::size_t w = n; w < P.size(); ++w) {
    if (P.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow)) continue;
    const double yw = P.position[2 * w + 1];
    if (yw < 0) {
      out.lower_min = std::min(out.lower_min, p->data[w]);
      out.lower_max = std::max(out.lower_max, p->data[w]);
      out.lower_rho_max = std::max(out.lower_rho_max, P.density[w]);
    } else if (yw > 0.01) {
      out.upper_min = std::min(out.upper_min, p->data[w]);
      out.upper_max = std::max(out.upper_max, p->data[w]);
    }
  }
  return out;
}

}  // namespace

TEST_CASE("dummy walls: pressure_floor bounds the extrapolated pressure of its own block only") {
  // Without a floor both die walls take the fluid's tension (p = c^2 (rho - rho0) = -16 kPa
  // at c = 40 m/s); with pressure_floor = 0 on the lower wall its particles hold p = 0 (the
  // density of p = 0, rho0) and push without pulling, while the upper wall keeps the tension.
  const WallPressures free = stretchedDie({});
  CHECK(free.fluid_p == doctest::Approx(-16000.0).epsilon(1e-9));
  CHECK(free.lower_min == doctest::Approx(free.fluid_p).epsilon(1e-6));
  CHECK(free.upper_min == doctest::Approx(free.fluid_p).epsilon(1e-6));

  const WallPressures floored = stretchedDie({"blocks[1].pressure_floor=0.0"});
  CHECK(floored.lower_min == 0.0);
  CHECK(floored.lower_max == 0.0);
  CHECK(floored.lower_rho_max == doctest::Approx(1000.0).epsilon(1e-12));
  CHECK(floored.upper_min == doctest::Approx(free.fluid_p).epsilon(1e-6));

  // A floor below the tension changes nothing; one above it is the wall's pressure.
  const WallPressures low = stretchedDie({"blocks[1].pressure_floor=-20000.0"});
  CHECK(low.lower_min == doctest::Approx(free.lower_min).epsilon(1e-12));
  const WallPressures high = stretchedDie({"blocks[2].pressure_floor=-5000.0"});
  CHECK(high.upper_min == -5000.0);
  CHECK(high.lower_min == doctest::Approx(free.fluid_p).epsilon(1e-6));
}

TEST_CASE("dummy walls: pressure_floor is refused where it has no meaning") {
  auto build = [](const std::vector<std::string>& overrides) {
    SceneHeader h;
    Config cfg = loadScene(kDie, overrides, h);
    Simulation<2> sim(cfg, h);
  };
  CHECK_THROWS_WITH_AS(build({"blocks[0].pressure_floor=0.0"}), doctest::Contains("no pressure_floor on a fluid block"),
                       InputError);
  CHECK_THROWS_WITH_AS(build({"blocks[1].pressure_floor=\"zero\""}), doctest::Contains("pressure_floor"), InputError);
  CHECK_THROWS_WITH_AS(build({"blocks[1].pressure_floor=0.0", "blocks[1].treatment=\"image\"",
                              "blocks[1].normal=[0.0, 1.0]"}),
                       doctest::Contains("dummy layers only"), InputError);
  CHECK_THROWS_WITH_AS(build({"blocks[1].pressure_floor=0.0", "solver.scheme=\"isph\""}),
                       doctest::Contains("pressure_floor is not implemented with solver.scheme = \"isph\""), InputError);
}
