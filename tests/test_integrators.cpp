// Integrators: observed temporal order on a smooth problem (every integrator, every ERK table
// in fixed-step mode), adaptive ARKODE error control, and Verlet lists under multi-stage
// methods giving the same results as a rebuild at every stage.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "vesph/sim/simulation.hpp"
#include "vesph/time/integrator.hpp"
#include "vesph/time/integrator_factory.hpp"

using namespace vesph;

namespace {

// A smooth problem laid out like the SPH state (positions | densities | velocities, D = 2):
// independent harmonic oscillators x' = v, v' = -w^2 x, and rho' = -x.v, with the exact
// solution x = x0 cos wt + v0/w sin wt, rho = rho0 - (|x|^2 - |x0|^2)/2.
struct Oscillators final : OdeSystem {
  static constexpr int D = 2;
  std::size_t n;
  double w;
  std::vector<double> x0, v0, rho0;
  std::uint64_t accepted = 0;

  Oscillators(std::size_t n_, double w_) : n(n_), w(w_) {
    for (std::size_t i = 0; i < n; ++i) {
      x0.push_back(std::cos(0.7 * i + 0.1));
      x0.push_back(0.5 * std::sin(1.3 * i));
      v0.push_back(0.3 * std::sin(0.9 * i + 0.4));
      v0.push_back(-0.8 + 0.1 * i);
      rho0.push_back(1.0 + 0.01 * i);
    }
  }
  std::size_t size() const override { return n * (2 * D + 1); }
  StateSegments segments() const override { return {0, n * D, n * (D + 1), n * (2 * D + 1)}; }
  void rhs(double, const double* y, double* f) override {
    const double* x = y;
    const double* v = y + n * (D + 1);
    for (std::size_t k = 0; k < n * D; ++k) {
      f[k] = v[k];
      f[n * (D + 1) + k] = -w * w * x[k];
    }
    for (std::size_t i = 0; i < n; ++i) f[n * D + i] = -(x[D * i] * v[D * i] + x[D * i + 1] * v[D * i + 1]);
  }
  StabilitySnapshot stability() const override { return {1.0, 0.0, 1.0, 0.0, 1.0}; }
  bool afterStep(double, double, double*) override {
    ++accepted;
    return true;
  }
  std::vector<double> initial() const {
    std::vector<double> y(size());
    for (std::size_t k = 0; k < n * D; ++k) {
      y[k] = x0[k];
      y[n * (D + 1) + k] = v0[k];
    }
    for (std::size_t i = 0; i < n; ++i) y[n * D + i] = rho0[i];
    return y;
  }
  // Max error over all components at time t.
  double error(const std::vector<double>& y, double t) const {
    double e = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double r2 = 0, r20 = 0;
      for (int a = 0; a < D; ++a) {
        const std::size_t k = D * i + a;
        const double x = x0[k] * std::cos(w * t) + v0[k] / w * std::sin(w * t);
        const double v = -x0[k] * w * std::sin(w * t) + v0[k] * std::cos(w * t);
        e = std::max({e, std::abs(y[k] - x), std::abs(y[n * (D + 1) + k] - v)});
        r2 += x * x;
        r20 += x0[k] * x0[k];
      }
      e = std::max(e, std::abs(y[n * D + i] - (rho0[i] - 0.5 * (r2 - r20))));
    }
    return e;
  }
};

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

std::unique_ptr<Integrator> build(const std::string& toml) {
  Config cfg = Config::fromString(toml, "test");
  ConfigTable t = cfg.root();
  auto integ = makeIntegrator(t, ReferenceScales{1.0, 1.0, 0.01, 1.0});
  cfg.rejectUnknownKeys();
  return integ;
}

// Error at t = 2 with a fixed step.
double errorWithStep(const std::string& type, const std::string& table, double dt, int* order = nullptr) {
  Oscillators sys(4, 1.3);
  auto integ = build("type = \"" + type + "\"\nstep = " + num(dt) + "\n" +
                     (table.empty() ? "" : "table = \"" + table + "\"\n"));
  if (order) *order = integ->order();
  std::vector<double> y = sys.initial();
  integ->start(sys, 0.0, y.data());
  REQUIRE(integ->advance(2.0));
  CHECK(integ->time() == 2.0);
  return sys.error(y, 2.0);
}

// Observed order from successive halvings of the step: the finest pair whose finer error is
// still well above round-off (1e-11; a 4-oscillator state integrated to t = 2 accumulates
// round-off of order 1e-14).
void checkOrder(const std::string& type, const std::string& table) {
  int q = 0;
  std::vector<double> dts = {0.4, 0.2, 0.1, 0.05, 0.025, 0.0125};
  std::vector<double> err;
  for (double dt : dts) err.push_back(errorWithStep(type, table, dt, &q));
  double observed = NAN;
  for (std::size_t k = 0; k + 1 < dts.size(); ++k)
    if (err[k + 1] > 1e-11) observed = std::log2(err[k] / err[k + 1]);
  MESSAGE(type << " " << table << ": nominal order " << q << ", observed " << observed << " (errors " << err[0]
               << " ... " << err.back() << ")");
  CHECK(std::abs(observed - q) < 0.3);
}

}  // namespace

TEST_CASE("integrators: leapfrog, midpoint and symplectic are second order on a smooth problem") {
  checkOrder("leapfrog", "");
  checkOrder("midpoint", "");
  checkOrder("symplectic", "");
}

TEST_CASE("integrators: symplectic takes one evaluation per step, reevaluates after a state change and resumes bit-identically") {
  // An oscillator system whose post-step hook may change the state (as the ISPH projection does).
  struct Hooked final : OdeSystem {
    Oscillators osc{3, 1.1};
    bool changes = false;
    std::size_t size() const override { return osc.size(); }
    StateSegments segments() const override { return osc.segments(); }
    void rhs(double t, const double* y, double* f) override { osc.rhs(t, y, f); }
    StabilitySnapshot stability() const override { return osc.stability(); }
    bool afterStep(double, double, double* y) override {
      if (changes) y[0] *= 0.999;  // a projection-like change of the state
      return true;
    }
    bool afterStepChangesState() const override { return changes; }
  };
  const std::string scene = "type = \"symplectic\"\nstep = 0.01\n";
  {
    Hooked sys;
    auto integ = build(scene);
    std::vector<double> y = sys.osc.initial();
    integ->start(sys, 0.0, y.data());
    REQUIRE(integ->advance(1.0));
    CHECK(integ->stats().steps == 100);
    CHECK(integ->stats().rhs_evals == 101);  // F at the start, then one per step
  }
  {
    Hooked sys;
    sys.changes = true;
    auto integ = build(scene);
    std::vector<double> y = sys.osc.initial();
    integ->start(sys, 0.0, y.data());
    REQUIRE(integ->advance(1.0));
    CHECK(integ->stats().rhs_evals == 201);  // the rates evaluated again after every change
  }
  // A run split at t = 0.5 with the carried rates restored equals the run in one piece exactly;
  // without them (rates evaluated at the state) it does not.
  Hooked sys;
  auto whole = build(scene);
  std::vector<double> y_whole = sys.osc.initial();
  whole->start(sys, 0.0, y_whole.data());
  REQUIRE(whole->advance(0.5));  // an output time in both runs, as with checkpoints at frames
  REQUIRE(whole->advance(1.0));
  auto first = build(scene);
  std::vector<double> y = sys.osc.initial();
  first->start(sys, 0.0, y.data());
  REQUIRE(first->advance(0.5));
  const std::vector<double> carried = first->carried();
  std::vector<double> y_fresh = y;
  auto second = build(scene);
  second->start(sys, 0.5, y.data());
  second->restoreCarried(carried);
  REQUIRE(second->advance(1.0));
  CHECK(y == y_whole);
  auto fresh = build(scene);
  fresh->start(sys, 0.5, y_fresh.data());
  REQUIRE(fresh->advance(1.0));
  CHECK(y_fresh != y_whole);
}

TEST_CASE("integrators: every ERK table in fixed-step mode reaches its nominal order") {
  // This also guards against SUNDIALS issue 311 (6.4.1 wrongly reuses a right-hand side for
  // some tables it takes as first-same-as-last): an affected table would lose its order.
  for (const ButcherTableInfo& t : erkTables()) {
    CAPTURE(t.name);
    checkOrder("arkode-fixed", t.name);
  }
}

TEST_CASE("integrators: adaptive ARKODE meets its tolerance and tighter tolerances cost more") {
  std::vector<double> errors;
  std::vector<std::uint64_t> evals;
  for (double rtol : {1e-4, 1e-7, 1e-10}) {
    Oscillators sys(4, 1.3);
    auto integ = build("type = \"arkode\"\ntable = \"DORMAND_PRINCE_7_4_5\"\nrtol = " + num(rtol) +
                       "\natol_position = " + num(rtol) + "\natol_density = " + num(rtol) +
                       "\natol_velocity = " + num(rtol) + "\n");
    std::vector<double> y = sys.initial();
    integ->start(sys, 0.0, y.data());
    // Several output times: the stop time must land exactly on each.
    for (double tout : {0.5, 1.0, 1.5, 2.0}) {
      REQUIRE(integ->advance(tout));
      CHECK(integ->time() == tout);
    }
    errors.push_back(sys.error(y, 2.0));
    evals.push_back(integ->stats().rhs_evals);
    CHECK(sys.accepted == integ->stats().steps);  // afterStep ran once per accepted step
    // Global error of a well-conditioned oscillator stays within a modest multiple of the
    // tolerance (local error control; x ~ 1 so rtol dominates).
    CHECK(errors.back() < 100 * rtol);
  }
  CHECK(errors[1] < errors[0]);
  CHECK(errors[2] < errors[1]);
  CHECK(evals[1] > evals[0]);
  CHECK(evals[2] > evals[1]);
}

TEST_CASE("integrators: the adaptive step never exceeds the stability limit") {
  // A system whose stability limit (acoustic: cfl*h/(c+v)) is far below what the error control
  // would choose: every accepted step must respect it.
  struct Limited final : OdeSystem {
    Oscillators osc{2, 1.0};
    double max_dt = 0;
    std::size_t size() const override { return osc.size(); }
    StateSegments segments() const override { return osc.segments(); }
    void rhs(double t, const double* y, double* f) override { osc.rhs(t, y, f); }
    StabilitySnapshot stability() const override { return {1e-3, 1.0, 0.0, 0.0, 0.0}; }  // limit = cfl*1e-3
    bool afterStep(double, double dt, double*) override {
      max_dt = std::max(max_dt, dt);
      return true;
    }
  } sys;
  auto integ = build("type = \"arkode\"\nrtol = 1e-3\ncfl = 0.5\n");
  std::vector<double> y = sys.osc.initial();
  integ->start(sys, 0.0, y.data());
  REQUIRE(integ->advance(0.05));
  CHECK(sys.max_dt <= 0.5e-3 * (1 + 1e-12));
  CHECK(sys.max_dt > 0.25e-3);  // and it uses the room it has
}

TEST_CASE("neighbours: Verlet lists with a skin give the results of a rebuild at every stage") {
  // The Poiseuille channel for 200 steps with a 7-stage Runge-Kutta method: once with the
  // default skin (lists rebuilt only when a particle moved more than skin/2) and once with no
  // skin (rebuilt at every stage where anything moved). Both must give the same state; only
  // the summation order inside a neighbour batch may differ.
  auto runWith = [](double skin, std::size_t& builds, std::uint64_t& evals) {
    SceneHeader h;
    Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml",
                           {"neighbours.skin=" + num(skin), "integrator.type=\"arkode-fixed\"",
                            "time.end=0.002", "output.times=[0.002]",
                            // a stronger drive than the demo: particles move 1.6 dx, past
                            // several skin/2 thresholds, in 200 steps
                            "effects.body_force.acceleration=[20.0, 0.0]", "effects.equation_of_state.sound_speed=0.5",
                            "checks.max_speed=10.0"},
                           h);
    Simulation<2> sim(cfg, h);
    const RunReport r = sim.run(RunOptions{"", true, false, 0});
    REQUIRE(r.status == RunStatus::ok);
    builds = sim.system().neighbours.builds();
    evals = r.summary["rhs_evals"].get<std::uint64_t>();
    return sim.state();
  };
  std::size_t builds_skin = 0, builds_every = 0;
  std::uint64_t evals_skin = 0, evals_every = 0;
  const std::vector<double> a = runWith(0.1, builds_skin, evals_skin);
  const std::vector<double> b = runWith(0.0, builds_every, evals_every);
  REQUIRE(a.size() == b.size());
  double scale = 0, diff = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::max(scale, std::abs(a[k]));
    diff = std::max(diff, std::abs(a[k] - b[k]));
  }
  INFO("builds with skin " << builds_skin << ", without " << builds_every << ", rhs evaluations " << evals_skin);
  CHECK(evals_skin == evals_every);
  // Without a skin the list is rebuilt at every evaluation where a particle moved: 6 of the
  // 7 Dormand-Prince stages (the first stage of a step sits at the state of the previous
  // step's last stage, which needs no rebuild).
  CHECK(builds_every + 1 >= evals_every * 6 / 7);
  CHECK(builds_skin >= 3);  // the skin lists were rebuilt during the run too
  CHECK(builds_skin * 10 < builds_every);
  CHECK(diff <= 1e-12 * scale);
}
