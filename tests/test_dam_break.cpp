// The dam break's parts (cases/dam_break_2d.toml at the CI size dx = 0.04 m): the Tait
// equation of state against its formula, the sound-speed rule c0 = coefsound sqrt(g H), the
// hydrostatic initial density (its pressure is rho0 g (H - y)), the gauges on that state, and
// the input checks of the new keys (docs/theory.md "Equation of state", "Hydrostatic initial
// density", "Gauges").
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "vesph/sim/gauges.hpp"
#include "vesph/sim/simulation.hpp"

using namespace vesph;

namespace {

const char* kDamBreak = VESPH_SOURCE_DIR "/cases/dam_break_2d.toml";
const std::vector<std::string> kCiSize = {"particles.spacing=0.04", "blocks[1].min=[-0.12,-0.12]",
                                          "blocks[1].max=[4.12,0.0]", "blocks[2].min=[-0.12,0.0]",
                                          "blocks[3].max=[4.12,3.0]"};
constexpr double kG = 9.81, kH = 2.0, kRho0 = 1000.0;

std::vector<std::string> with(std::vector<std::string> more) {
  std::vector<std::string> all = kCiSize;
  all.insert(all.end(), more.begin(), more.end());
  return all;
}

// The fluid's pressures after one evaluation of the initial state.
struct Initial {
  SceneHeader h;
  Config cfg;
  Simulation<2> sim;
  explicit Initial(const std::vector<std::string>& overrides)
      : cfg(loadScene(kDamBreak, overrides, h)), sim(cfg, h) {
    std::vector<double> y = sim.state(), ydot(y.size());
    sim.system().evaluate(0.0, y.data(), ydot.data());
  }
  const std::vector<double>& pressure() { return sim.system().particles.fields.find("pressure")->data; }
};

std::string inputError(const std::vector<std::string>& overrides) {
  try {
    SceneHeader h;
    Config cfg = loadScene(kDamBreak, overrides, h);
    Simulation<2> sim(cfg, h);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("Tait equation of state: p = B ((rho/rho0)^7 - 1), B = c0^2 rho0 / 7, c0 = 20 sqrt(g H)") {
  Initial run(kCiSize);
  const PressureModel* m = run.sim.system().pressureModel();
  REQUIRE(m != nullptr);
  const double c0 = 20.0 * std::sqrt(kG * kH);
  CHECK(m->soundSpeed() == doctest::Approx(c0).epsilon(1e-14));
  // The rule's design values: eq. (3.38) with V = sqrt(g H), delta = 1/coefsound^2.
  CHECK(m->designVelocity() == doctest::Approx(std::sqrt(kG * kH)).epsilon(1e-14));
  CHECK(m->designDensityVariation() == doctest::Approx(1.0 / 400.0).epsilon(1e-14));
  const double B = c0 * c0 * kRho0 / 7.0;
  for (double ratio : {0.97, 0.995, 1.0, 1.003, 1.02, 1.1}) {
    const double rho = ratio * kRho0;
    const double p = B * (std::pow(ratio, 7.0) - 1.0);
    CHECK(m->pressure(rho) == doctest::Approx(p).epsilon(1e-13).scale(B));
    CHECK(m->densityFor(p) == doctest::Approx(rho).epsilon(1e-13));
  }
  // Linear near rho0 with slope c0^2 (the sound speed at rest density).
  const double d = 1e-6 * kRho0;
  CHECK((m->pressure(kRho0 + d) - m->pressure(kRho0 - d)) / (2 * d) == doctest::Approx(c0 * c0).epsilon(1e-9));
  // Below Tait's least pressure p0 - B the inverse stays positive.
  CHECK(m->densityFor(-2 * B) > 0.1 * kRho0);
  // gamma is a key; the reference pressure shifts p.
  Initial g5(with({"effects.equation_of_state.gamma=5.0", "effects.equation_of_state.reference_pressure=100.0"}));
  const PressureModel* m5 = g5.sim.system().pressureModel();
  CHECK(m5->pressure(1.01 * kRho0) ==
        doctest::Approx(100.0 + c0 * c0 * kRho0 / 5.0 * (std::pow(1.01, 5.0) - 1.0)).epsilon(1e-13));
}

TEST_CASE("hydrostatic initial density: the initial pressure is rho0 g (H - y), Tait and linear") {
  for (const auto& extra : {std::vector<std::string>{},
                            std::vector<std::string>{"effects.equation_of_state={ sound_speed = 60.0 }"}}) {
    CAPTURE(extra.size());
    Initial run(with(extra));
    const ParticleSet<2>& P = run.sim.system().particles;
    const std::vector<double>& p = run.pressure();
    double worst = 0;
    for (std::size_t i = 0; i < P.n_moving; ++i) {
      const double y = P.position[2 * i + 1];
      worst = std::max(worst, std::abs(p[i] - kRho0 * kG * (kH - y)));
      CHECK(P.mass[i] == doctest::Approx(kRho0 * 0.04 * 0.04).epsilon(1e-14));  // the mass stays rho0 dx^2
    }
    MESSAGE("max |p - rho0 g (H - y)| / (rho0 g H) = ", worst / (kRho0 * kG * kH));
    CHECK(worst < 1e-10 * kRho0 * kG * kH);
  }
  // A free surface given above the block: every pressure higher by rho0 g (2.5 - 2).
  Initial high(with({"blocks[0].surface_height=2.5"}));
  const ParticleSet<2>& P = high.sim.system().particles;
  CHECK(high.pressure()[0] == doctest::Approx(kRho0 * kG * (2.5 - P.position[1])).epsilon(1e-10));
  // Without the key the fluid starts at rho0 (p = 0).
  Initial plain(with({"blocks[0].hydrostatic=false"}));
  CHECK(plain.pressure()[0] == 0.0);
}

TEST_CASE("gauges on the hydrostatic column: point pressure, elevation, front") {
  Initial run(kCiSize);
  Config gcfg = Config::fromString(
      "[[gauges]]\nname = \"p\"\ntype = \"point\"\nposition = [0.5, 1.0]\n"
      "[[gauges]]\nname = \"eta\"\ntype = \"elevation\"\nposition = [0.5, 0.0]\n"
      "[[gauges]]\nname = \"dry\"\ntype = \"elevation\"\nposition = [2.5, 0.0]\n"
      "[[gauges]]\nname = \"front\"\ntype = \"front\"\n",
      "gauges.toml");
  ConfigTable root = gcfg.root();
  Gauges<2> gauges;
  const SphSystem<2>& sys = run.sim.system();
  gauges.read(root, sys.domain, 0.04);
  const std::vector<GaugeSeries> series = gauges.series();
  REQUIRE(series.size() == 4);
  CHECK(series[0].columns == std::vector<std::string>{"time", "pressure", "velocity_x", "velocity_y", "density", "kernel_sum"});
  const auto rows = gauges.evaluate(0.25, sys.particles, sys.kernel, sys.domain);
  REQUIRE(rows.size() == 4);
  CHECK(rows[0][0] == 0.25);
  // A linear pressure on a lattice symmetric about the point: the Shepard interpolation would be
  // exact with equal volumes; the volumes m/rho_j vary with depth by (dp/dy) dx / c0^2 ~ 5e-5
  // across a support, which weights the deeper side more: measured 1e-6 relative.
  CHECK(rows[0][1] == doctest::Approx(kRho0 * kG * (kH - 1.0)).epsilon(1e-5));
  CHECK(rows[0][2] == 0.0);
  CHECK(rows[0][5] == doctest::Approx(1.0).epsilon(0.02));  // a full support: kernel sum ~ 1
  // The surface at H = 2 m within a quarter spacing; a dry foot gives NaN; the front is the
  // last particle centre, 1 - dx/2.
  CHECK(std::abs(rows[1][1] - kH) < 0.25 * 0.04);
  CHECK(std::isnan(rows[2][1]));
  CHECK(rows[3][1] == doctest::Approx(1.0 - 0.02).epsilon(1e-12));
}

TEST_CASE("dam-break keys: input checks") {
  CHECK(inputError(with({"effects.equation_of_state.form=\"cubic\""})).find("expected one of: linear, tait") != std::string::npos);
  CHECK(inputError(with({"effects.equation_of_state.sound_speed.phi=4.0"})).find("no phi with coefsound") != std::string::npos);
  CHECK(inputError(with({"effects.equation_of_state.sound_speed.coefsound=0.5"})).find("coefsound") != std::string::npos);
  CHECK(inputError(with({"effects.equation_of_state={ sound_speed = 60.0, gamma = 7.0 }"})).find("no gamma with form") !=
        std::string::npos);
  CHECK(inputError(with({"effects.body_force.acceleration=[0.0,0.0]"})).find("needs a body acceleration") != std::string::npos);
  CHECK(inputError(with({"blocks[1].hydrostatic=true"})).find("no hydrostatic on a wall block") != std::string::npos);
  CHECK(inputError(with({"blocks[0].hydrostatic=false", "blocks[0].surface_height=2.0"})).find("without hydrostatic") !=
        std::string::npos);
  CHECK(inputError(with({"effects.viscosity={}"})).find("effects.viscosity needs the viscosity mu") != std::string::npos);
  CHECK(inputError(with({"effects.viscosity={}", "fluid.viscosity=1e-3"})).empty());
  CHECK(inputError(with({"gauges[0].name=\"a/b\""})).find("gauges[0].name") != std::string::npos);
  CHECK(inputError(with({"gauges[1].name=\"front\""})).find("is taken") != std::string::npos);
  CHECK(inputError(with({"gauges[1].position=[9.0,0.0]"})).find("inside the domain") != std::string::npos);
  CHECK(inputError(with({"gauges[0].position=[1.0,0.0]"})).find("no position for a front gauge") != std::string::npos);
}
