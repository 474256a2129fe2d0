// Particle-count changes between steps (inflow, outflow; docs/architecture.md "Particle count may change
// during a run"): the particle set's remap of arrays and fields, and every integrator going on
// correctly after its state was resized mid-run (ARKODE through ERKStepResize).
#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "vesph/core/particles.hpp"
#include "vesph/io/config.hpp"
#include "vesph/time/integrator.hpp"
#include "vesph/time/integrator_factory.hpp"

using namespace vesph;

TEST_CASE("open boundaries: the particle set remaps arrays and fields by range") {
  ParticleSet<2> p;
  // moving 0..3 (ids 10..13), fixed 4..6 (ids 20..22; 6 is an inflow buffer particle)
  for (int i = 0; i < 4; ++i)
    p.add(Vec<2>(i, 0.5 * i), Vec<2>(1.0 + i, 0.0), 1000.0 + i, 2.0, ParticleKind::fluid, 10 + i);
  for (int k = 0; k < 3; ++k)
    p.add(Vec<2>(-1.0 - k, 0.0), Vec<2>(0.0, 0.0), 990.0 + k, 2.0, k == 2 ? ParticleKind::inflow : ParticleKind::wall,
          20 + k);
  Field& all = p.fields.require("stress", 3, Field::Range::all);
  Field& moving = p.fields.require("gradient", 1, Field::Range::moving);
  Field& fixed = p.fields.require("wall_velocity", 2, Field::Range::fixed);
  p.resizeFields();
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) all.data[3 * i + c] = 100.0 * i + c;
  for (std::size_t i = 0; i < 4; ++i) moving.data[i] = -1.0 - i;
  for (std::size_t k = 0; k < 6; ++k) fixed.data[k] = 7.0 + k;

  // Remove moving particles 0 and 2, release the buffer particle (old index 6).
  ParticleRemap m;
  m.old_size = p.size();
  m.old_moving = p.n_moving;
  m.source = {1, 3, 6};
  m.released_ids = {23};
  p.remapMoving(m);

  REQUIRE(p.n_moving == 3);
  REQUIRE(p.size() == 6);
  CHECK(p.id == std::vector<std::uint64_t>{11, 13, 23, 20, 21, 22});
  CHECK(p.kind[2] == static_cast<std::uint8_t>(ParticleKind::fluid));   // released: fluid now
  CHECK(p.kind[5] == static_cast<std::uint8_t>(ParticleKind::inflow));  // the buffer particle stays
  CHECK(p.position[2 * 2] == doctest::Approx(-3.0));                      // the buffer particle's position
  CHECK(p.density[2] == doctest::Approx(992.0));
  CHECK(p.velocity[2 * 1] == doctest::Approx(4.0));                       // old particle 3
  CHECK(p.density[3] == doctest::Approx(990.0));                          // fixed keep their order
  CHECK(all.data.size() == 18);
  CHECK(all.data[3 * 0 + 1] == doctest::Approx(101.0));  // old 1
  CHECK(all.data[3 * 2 + 2] == doctest::Approx(602.0));  // released: the buffer particle's value
  CHECK(all.data[3 * 5 + 0] == doctest::Approx(600.0));  // the buffer particle itself
  CHECK(moving.data == std::vector<double>{-2.0, -4.0, 0.0});  // a released particle has no moving-only value
  CHECK(fixed.data.size() == 6);
  CHECK(fixed.data[5] == doctest::Approx(12.0));
  CHECK(m.fixedIndex(6) == 5);

  ParticleRemap wrong = m;  // made for the old set
  CHECK_THROWS_AS(p.remapMoving(wrong), std::logic_error);
}

namespace {

// Independent oscillators x' = v, v' = -w^2 x laid out like the SPH state (D = 1: positions |
// densities | velocities; the density rho' = 0 stays constant). At the first accepted step at
// or after t_resize, oscillator 1 is removed and two new ones join with their own initial
// values at that time: the state is rewritten into a new buffer of a different length.
struct ChangingOscillators final : OdeSystem {
  struct Member {
    double x0, v0, born;
  };
  std::vector<Member> members;
  double w = 1.7, t_resize = 0.5;
  bool pending = false, done = false;
  int resizes = 0;
  std::vector<double> storage;

  ChangingOscillators() {
    for (int i = 0; i < 5; ++i) members.push_back({std::cos(0.7 * i), 0.3 * std::sin(1.1 * i + 0.2), 0.0});
    storage = pack(0.0);
  }
  std::size_t n() const { return members.size(); }
  std::size_t size() const override { return 3 * n(); }
  StateSegments segments() const override { return {0, n(), 2 * n(), 3 * n()}; }
  void rhs(double, const double* y, double* f) override {
    const std::size_t m = n();
    for (std::size_t i = 0; i < m; ++i) {
      f[i] = y[2 * m + i];
      f[m + i] = 0.0;
      f[2 * m + i] = -w * w * y[i];
    }
  }
  StabilitySnapshot stability() const override { return {1.0, 0.0, 1.0, 0.0, 1.0}; }
  bool afterStep(double t, double, double*) override {
    if (!done && t >= t_resize) pending = true;
    return true;
  }
  bool mayResize() const override { return true; }
  bool resizePending() const override { return pending; }
  double* resizeState(double t, double* y) override {
    const std::size_t m = n();
    std::vector<double> x(y, y + m), rho(y + m, y + 2 * m), v(y + 2 * m, y + 3 * m);
    members.erase(members.begin() + 1);
    x.erase(x.begin() + 1);
    rho.erase(rho.begin() + 1);
    v.erase(v.begin() + 1);
    for (double a : {0.4, -0.9}) {
      members.push_back({a, 0.5 * a, t});
      x.push_back(a);
      rho.push_back(1.0);
      v.push_back(0.5 * a);
    }
    std::vector<double> fresh;
    fresh.insert(fresh.end(), x.begin(), x.end());
    fresh.insert(fresh.end(), rho.begin(), rho.end());
    fresh.insert(fresh.end(), v.begin(), v.end());
    storage.swap(fresh);  // a new buffer: the old pointer is invalid from here on
    pending = false;
    done = true;
    ++resizes;
    return storage.data();
  }
  std::vector<double> pack(double t) const {
    std::vector<double> y(3 * n());
    for (std::size_t i = 0; i < n(); ++i) {
      y[i] = members[i].x0;
      y[n() + i] = 1.0;
      y[2 * n() + i] = members[i].v0;
    }
    (void)t;
    return y;
  }
  double error(double t) const {
    double e = 0;
    const std::size_t m = n();
    for (std::size_t i = 0; i < m; ++i) {
      const double s = t - members[i].born;
      const double x = members[i].x0 * std::cos(w * s) + members[i].v0 / w * std::sin(w * s);
      const double v = -members[i].x0 * w * std::sin(w * s) + members[i].v0 * std::cos(w * s);
      e = std::max({e, std::abs(storage[i] - x), std::abs(storage[2 * m + i] - v), std::abs(storage[m + i] - 1.0)});
    }
    return e;
  }
};

}  // namespace

TEST_CASE("open boundaries: every integrator goes on correctly after the state is resized") {
  struct Case {
    const char* toml;
    double bound;
  };
  const Case cases[] = {
      {"type = \"leapfrog\"\nstep = 1e-3\n", 1e-5},
      {"type = \"midpoint\"\nstep = 1e-3\n", 1e-5},
      {"type = \"arkode-fixed\"\nstep = 1e-2\n", 1e-8},
      {"type = \"arkode\"\nrtol = 1e-9\natol_position = 1e-11\natol_velocity = 1e-11\natol_density = 1e-11\n", 1e-7},
  };
  for (const Case& c : cases) {
    const std::string scene = c.toml;
    CAPTURE(scene);
    ChangingOscillators sys;
    Config cfg = Config::fromString(c.toml, "test");
    ConfigTable t = cfg.root();
    auto integ = makeIntegrator(t, ReferenceScales{1.0, 1.0, 0.01, 1.0});
    cfg.rejectUnknownKeys();
    integ->start(sys, 0.0, sys.storage.data());
    REQUIRE(integ->advance(1.0));
    REQUIRE(integ->advance(2.0));
    CHECK(sys.resizes == 1);
    CHECK(sys.n() == 6);
    CHECK(integ->time() == 2.0);
    const double err = sys.error(2.0);
    MESSAGE(integ->name() << ": error after the resize " << err);
    CHECK(err < c.bound);
  }
}
