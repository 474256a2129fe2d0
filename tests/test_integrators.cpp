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

namespace {

// The oscillators with a linear damping split off as the implicit part, stiff-free but
// position-dependent like the SPH viscous term: v' = -w^2 x (explicit) - k(x) v (implicit),
// k = 0.4 (1 + |x_i|^2) per oscillator, no position or density rate in the implicit part.
struct DampedOscillators final : OdeSystem {
  Oscillators osc{4, 1.3};
  double damping = 0.4;  // k = damping (1 + |x_i|^2); stiff when damping dt >> 1
  std::size_t size() const override { return osc.size(); }
  StateSegments segments() const override { return osc.segments(); }
  void rhs(double t, const double* y, double* f) override {
    std::vector<double> fi(size());
    rhsPart(RhsPart::explicit_part, t, y, f);
    rhsPart(RhsPart::implicit_part, t, y, fi.data());
    for (std::size_t k = 0; k < size(); ++k) f[k] += fi[k];
  }
  void rhsPart(RhsPart part, double t, const double* y, double* f) override {
    if (part == RhsPart::explicit_part) return osc.rhs(t, y, f);
    const std::size_t n = osc.n, D = Oscillators::D;
    const bool diagonal = part == RhsPart::implicit_diagonal;  // d f_I / dv = -k
    for (std::size_t k = 0; k < size(); ++k) f[k] = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double k = damping * (1.0 + y[D * i] * y[D * i] + y[D * i + 1] * y[D * i + 1]);
      for (std::size_t a = 0; a < D; ++a) f[n * (D + 1) + D * i + a] = -k * (diagonal ? 1.0 : y[n * (D + 1) + D * i + a]);
    }
  }
  StabilitySnapshot stability() const override { return osc.stability(); }
  bool afterStep(double t, double dt, double* y) override { return osc.afterStep(t, dt, y); }
};

// The damped oscillators at t = 2 by a 6th-order table at a step 12x below the finest tested.
const std::vector<double>& dampedReference() {
  static const std::vector<double> y = [] {
    DampedOscillators sys;
    auto integ = build("type = \"arkode-fixed\"\ntable = \"VERNER_8_5_6\"\nstep = 0.001\n");
    std::vector<double> y0 = sys.osc.initial();
    integ->start(sys, 0.0, y0.data());
    REQUIRE(integ->advance(2.0));
    return y0;
  }();
  return y;
}

double imexErrorWithStep(const std::string& table, double dt, int* order) {
  DampedOscillators sys;
  // Tight solver tolerances: the Newton and Krylov errors stay far below the truncation error.
  auto integ = build("type = \"arkode-imex-fixed\"\nstep = " + num(dt) + "\ntable = \"" + table +
                     "\"\nrtol = 1e-13\natol_position = 1e-13\natol_density = 1e-13\natol_velocity = 1e-13\n");
  *order = integ->order();
  std::vector<double> y = sys.osc.initial();
  integ->start(sys, 0.0, y.data());
  REQUIRE(integ->advance(2.0));
  CHECK(integ->time() == 2.0);
  const std::vector<double>& ref = dampedReference();
  double e = 0;
  for (std::size_t k = 0; k < y.size(); ++k) e = std::max(e, std::abs(y[k] - ref[k]));
  return e;
}

}  // namespace

TEST_CASE("integrators: every IMEX pair in fixed-step mode reaches its nominal order") {
  // The implicit part depends on the positions, which the Jacobian-vector product freezes:
  // the Newton iteration must still converge to the stage solution, or the order drops.
  for (const ArkPairInfo& p : arkPairs()) {
    CAPTURE(p.name);
    int q = 0;
    std::vector<double> dts = {0.4, 0.2, 0.1, 0.05, 0.025, 0.0125};
    std::vector<double> err;
    for (double dt : dts) err.push_back(imexErrorWithStep(p.name, dt, &q));
    double observed = NAN;
    for (std::size_t k = 0; k + 1 < dts.size(); ++k)
      if (err[k + 1] > 1e-11) observed = std::log2(err[k] / err[k + 1]);
    MESSAGE("arkode-imex-fixed " << p.name << ": nominal order " << q << ", observed " << observed << " (errors "
                                 << err[0] << " ... " << err.back() << ")");
    CHECK(std::abs(observed - q) < 0.3);
  }
  // The table names of a pair name the pair.
  CHECK(build("type = \"arkode-imex-fixed\"\nstep = 0.1\ntable = \"ARK436L2SA_DIRK_6_3_4\"\n")->order() == 4);
}

TEST_CASE("integrators: semi-implicit is second order, with and without a split, and L-stable on stiff damping") {
  // Without a split (f_I = 0) the implicit half steps are the identity: the midpoint rule's
  // states, bit for bit, at the same step.
  checkOrder("semi-implicit", "");
  {
    Oscillators a(4, 1.3), b(4, 1.3);
    std::vector<double> ya = a.initial(), yb = b.initial();
    auto semi = build("type = \"semi-implicit\"\nstep = 0.05\n");
    auto midpoint = build("type = \"midpoint\"\nstep = 0.05\n");
    semi->start(a, 0.0, ya.data());
    midpoint->start(b, 0.0, yb.data());
    REQUIRE(semi->advance(2.0));
    REQUIRE(midpoint->advance(2.0));
    CHECK(ya == yb);
    CHECK(semi->stats().steps == midpoint->stats().steps);
  }
  // The damped oscillators split as for arkode-imex: second order (Strang splitting of two
  // second-order sub-steps).
  auto errorAt = [](double damping, double dt, const std::vector<double>& ref, IntegratorStats* stats = nullptr) {
    DampedOscillators sys;
    sys.damping = damping;
    auto integ = build("type = \"semi-implicit\"\nstep = " + num(dt) + "\nrtol = 1e-12\n");
    std::vector<double> y = sys.osc.initial();
    integ->start(sys, 0.0, y.data());
    REQUIRE(integ->advance(2.0));
    CHECK(integ->time() == 2.0);
    CHECK(sys.osc.accepted == integ->stats().steps);
    if (stats) *stats = integ->stats();
    double e = 0;
    for (std::size_t k = 0; k < y.size(); ++k) e = std::max(e, std::abs(y[k] - ref[k]));
    return e;
  };
  const std::vector<double> dts = {0.4, 0.2, 0.1, 0.05, 0.025, 0.0125};
  {
    std::vector<double> err;
    for (double dt : dts) err.push_back(errorAt(0.4, dt, dampedReference()));
    const double observed = std::log2(err[err.size() - 2] / err.back());
    MESSAGE("semi-implicit, damped oscillators: observed order " << observed << " (errors " << err[0] << " ... "
                                                                 << err.back() << ")");
    CHECK(std::abs(observed - 2) < 0.3);
  }
  // Stiff damping (k dt from 12 to 400 at these steps; the explicit limit is dt < 2/k): stable
  // and converging, but at first order while k dt >> 1 — the splitting's order reduction: the
  // quasi-steady balance v = -w^2 x / k between the explicit force and the stiff damping is
  // not kept inside a step (docs/theory.md §9.6). Reference: the same scheme at dt = 1e-4.
  {
    const double damping = 1000;
    DampedOscillators sys;
    sys.damping = damping;
    auto fine = build("type = \"semi-implicit\"\nstep = 1e-4\nrtol = 1e-12\n");
    std::vector<double> ref = sys.osc.initial();
    fine->start(sys, 0.0, ref.data());
    REQUIRE(fine->advance(2.0));
    std::vector<double> err;
    IntegratorStats stats;
    for (double dt : dts) err.push_back(errorAt(damping, dt, ref, &stats));
    const double observed = std::log2(err[err.size() - 2] / err.back());
    MESSAGE("semi-implicit, stiff damped oscillators: errors " << err[0] << " ... " << err.back()
                                                               << ", observed order at the finest steps " << observed);
    for (std::size_t k = 0; k + 1 < err.size(); ++k) CHECK(err[k + 1] < err[k]);
    CHECK(err.back() < 0.03);
    CHECK(observed > 0.9);
    // Per step: 2 explicit evaluations, 1 diagonal, per half step 2 stages of f_I and one
    // product J w each (the Jacobi preconditioner is exact for this diagonal J); 1 + 1 at the
    // start (F_E, the first diagonal).
    CHECK(stats.rhs_evals == 2 + stats.steps * (2 + 1 + 2 * 4));
  }
  // L-stability: at k tau = 5e4 one step leaves the velocities at the quasi-steady balance's
  // size (|v| <= w^2 |x| dt / (k tau)-ish), where Crank-Nicolson would return about -v.
  {
    DampedOscillators sys;
    sys.damping = 1e6;
    auto integ = build("type = \"semi-implicit\"\nstep = 0.1\n");
    std::vector<double> y = sys.osc.initial();
    integ->start(sys, 0.0, y.data());
    REQUIRE(integ->advance(0.1));
    const StateSegments seg = sys.segments();
    double v0 = 0, v1 = 0;
    for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k) {
      v0 = std::max(v0, std::abs(sys.osc.initial()[k]));
      v1 = std::max(v1, std::abs(y[k]));
    }
    MESSAGE("semi-implicit, k tau = 5e4: max |v| " << v0 << " -> " << v1 << " in one step");
    CHECK(v1 < 1e-4 * v0);
  }
}

TEST_CASE("integrators: semi-implicit resumes bit-identically from its carried rate") {
  DampedOscillators sys;
  const std::string scene = "type = \"semi-implicit\"\nstep = 0.01\n";
  auto whole = build(scene);
  std::vector<double> y_whole = sys.osc.initial();
  whole->start(sys, 0.0, y_whole.data());
  REQUIRE(whole->advance(0.5));
  REQUIRE(whole->advance(1.0));
  auto first = build(scene);
  std::vector<double> y = sys.osc.initial();
  first->start(sys, 0.0, y.data());
  REQUIRE(first->advance(0.5));
  const std::vector<double> carried = first->carried();
  CHECK(carried.size() == y.size());
  auto second = build(scene);
  second->start(sys, 0.5, y.data());
  second->restoreCarried(carried);
  REQUIRE(second->advance(1.0));
  CHECK(y == y_whole);
}

TEST_CASE("integrators: adaptive IMEX ARKODE meets its tolerance") {
  std::vector<double> errors;
  for (double rtol : {1e-4, 1e-7}) {
    DampedOscillators sys;
    auto integ = build("type = \"arkode-imex\"\nrtol = " + num(rtol) + "\natol_position = " + num(rtol) +
                       "\natol_density = " + num(rtol) + "\natol_velocity = " + num(rtol) + "\n");
    std::vector<double> y = sys.osc.initial();
    integ->start(sys, 0.0, y.data());
    for (double tout : {0.5, 1.0, 2.0}) {
      REQUIRE(integ->advance(tout));
      CHECK(integ->time() == tout);
    }
    const std::vector<double>& ref = dampedReference();
    double e = 0;
    for (std::size_t k = 0; k < y.size(); ++k) e = std::max(e, std::abs(y[k] - ref[k]));
    errors.push_back(e);
    CHECK(sys.osc.accepted == integ->stats().steps);
    CHECK(e < 100 * rtol);
  }
  CHECK(errors[1] < errors[0]);
}

TEST_CASE("integrators: the IMEX split is exact and frees the step from the viscous, relaxation and elastic limits") {
  // Oldroyd-B start-up channel (viscous solvent, walls, elastic stress): the explicit and the
  // implicit part add up to the full right-hand side to round-off, at a state with flow and
  // stress (after a few steps).
  SceneHeader h;
  Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/startup_channel_oldroyd_b.toml",
                         {"time.end=0.002", "output.times=[0.002]"}, h);
  Simulation<2> sim(cfg, h);
  REQUIRE(sim.run(RunOptions{"", true, false, 0}).status == RunStatus::ok);
  SphSystem<2>& sys = sim.system();
  const std::vector<double> y = sim.state();
  std::vector<double> full(y.size()), fe(y.size()), fi(y.size());
  sys.rhsPart(RhsPart::full, 0.002, y.data(), full.data());
  const StabilitySnapshot full_stability = sys.stability();
  sys.rhsPart(RhsPart::implicit_part, 0.002, y.data(), fi.data());
  sys.rhsPart(RhsPart::explicit_part, 0.002, y.data(), fe.data());
  const StateSegments seg = sys.segments();
  // per segment: positions, densities, velocities, stresses
  const std::size_t bounds[] = {seg.position_begin, seg.position_end, seg.velocity_begin, seg.velocity_end, y.size()};
  for (int s = 0; s < 4; ++s) {
    double scale = 0, diff = 0, implicit_size = 0;
    for (std::size_t k = bounds[s]; k < bounds[s + 1]; ++k) {
      scale = std::max(scale, std::abs(full[k]));
      diff = std::max(diff, std::abs(fe[k] + fi[k] - full[k]));
      implicit_size = std::max(implicit_size, std::abs(fi[k]));
    }
    CAPTURE(s);
    CHECK(scale > 0);
    CHECK(diff <= 1e-13 * scale);
    // positions and densities have no implicit rate; velocities and stresses do
    CHECK((s < 2 ? implicit_size == 0 : implicit_size > 0));
  }
  // The Jacobian's diagonal (the Jacobi preconditioner of arkode-imex) against a probe of f_I
  // along one velocity and one stress component of a particle far from the walls (the diagonal
  // leaves out the wall velocities' dependence on the fluid's).
  {
    std::vector<double> diagonal(y.size()), probed(y.size()), shifted = y;
    sys.rhsPart(RhsPart::implicit_diagonal, 0.002, y.data(), diagonal.data());
    std::size_t centre = 0;
    for (std::size_t i = 0; i < sys.particles.n_moving; ++i)
      if (std::abs(y[2 * i + 1] - 5e-4) < std::abs(y[2 * centre + 1] - 5e-4)) centre = i;
    for (std::size_t k : {seg.velocity_begin + 2 * centre, seg.velocity_end + 3 * centre + 1}) {
      CAPTURE(k);
      const double step = 1e-3;
      shifted = y;
      shifted[k] += step;
      sys.rhsPart(RhsPart::implicit_part, 0.002, shifted.data(), probed.data());
      const double exact = (probed[k] - fi[k]) / step;
      CHECK(diagonal[k] < 0);
      CHECK(std::abs(diagonal[k] - exact) <= 1e-6 * std::abs(exact));
    }
    for (std::size_t k = 0; k < seg.velocity_begin; ++k) REQUIRE(diagonal[k] == 0);
  }
  // The explicit part's stability inputs lack the viscous and relaxation terms and the elastic
  // wave (the stress divergence and the linear part of the rate are implicit).
  const StabilitySnapshot explicit_stability = sys.explicitStability();
  CHECK(full_stability.kinematic_viscosity > 0);
  CHECK(full_stability.relaxation_time > 0);
  CHECK(explicit_stability.kinematic_viscosity == 0);
  CHECK(explicit_stability.relaxation_time == 0);
  CHECK(explicit_stability.sound_speed == full_stability.sound_speed);
  CHECK(full_stability.elastic_wave_speed > 0);
  CHECK(explicit_stability.elastic_wave_speed == 0);
  const StepLimits limits = stepLimits(explicit_stability, StepControl{});
  CHECK(limits.viscous == std::numeric_limits<double>::infinity());
  CHECK(limits.relaxation == std::numeric_limits<double>::infinity());
}

TEST_CASE("integrators: the stress form of the viscous force is implicit under the IMEX split") {
  // The Poiseuille channel with [effects.viscosity] form = "stress" (Morris' Laplacian plus the
  // divergence of mu kappa^T, kappa renormalised): the whole viscous force, kappa^T part
  // included, is in f_I (the velocity gradient computed in the implicit evaluations too), f_E
  // carries no viscous limit, and f_E + f_I = f to round-off.
  SceneHeader h;
  Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml",
                         {"time.end=0.002", "output.times=[0.002]", "effects.viscosity.form=\"stress\"",
                          "effects.velocity_gradient.form=\"renormalised\""},
                         h);
  Simulation<2> sim(cfg, h);
  REQUIRE(sim.run(RunOptions{"", true, false, 0}).status == RunStatus::ok);
  SphSystem<2>& sys = sim.system();
  // The channel's flow is parallel and x-periodic, where the kappa^T sums cancel: a velocity
  // perturbation that is not divergence-free gives them work (mu grad div v).
  std::vector<double> y = sim.state();
  const StateSegments seg = sys.segments();
  for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k) y[k] += 1e-4 * std::sin(0.37 * static_cast<double>(k));
  std::vector<double> full(y.size()), fe(y.size()), fi(y.size());
  sys.rhsPart(RhsPart::full, 0.002, y.data(), full.data());
  sys.rhsPart(RhsPart::implicit_part, 0.002, y.data(), fi.data());
  sys.rhsPart(RhsPart::explicit_part, 0.002, y.data(), fe.data());
  double scale = 0, diff = 0, implicit_size = 0;
  for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k) {
    scale = std::max(scale, std::abs(full[k]));
    diff = std::max(diff, std::abs(fe[k] + fi[k] - full[k]));
    implicit_size = std::max(implicit_size, std::abs(fi[k]));
  }
  CHECK(implicit_size > 0);
  CHECK(diff <= 1e-13 * scale);
  // f_I is the Laplacian plus the kappa^T part: at the same state the Laplacian form's implicit
  // rate differs.
  {
    Config lap = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml",
                           {"time.end=0.002", "output.times=[0.002]"}, h);
    Simulation<2> lsim(lap, h);
    REQUIRE(lsim.run(RunOptions{"", true, false, 0}).status == RunStatus::ok);
    REQUIRE(lsim.state().size() == y.size());
    std::vector<double> fl(y.size());
    lsim.system().rhsPart(RhsPart::implicit_part, 0.002, y.data(), fl.data());
    double change = 0;
    for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k) change = std::max(change, std::abs(fi[k] - fl[k]));
    CHECK(change > 1e-3 * implicit_size);
  }
  // f_I is linear in the velocities (its kappa too): f_I(2 y_v) = 2 f_I(y_v) when the walls'
  // extrapolated velocities follow the fluid's.
  {
    std::vector<double> doubled = y, f2(y.size());
    for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k) doubled[k] *= 2;
    sys.rhsPart(RhsPart::implicit_part, 0.002, doubled.data(), f2.data());
    double nonlinearity = 0;
    for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k)
      nonlinearity = std::max(nonlinearity, std::abs(f2[k] - 2 * fi[k]));
    CHECK(nonlinearity <= 1e-12 * implicit_size);
  }
  CHECK(sys.stability().kinematic_viscosity > 0);
  CHECK(sys.explicitStability().kinematic_viscosity == 0);
}

TEST_CASE("integrators: the assembled velocity operator of the IMEX preconditioner is the viscous Jacobian") {
  // The Poiseuille channel after a few steps: L (OdeSystem::implicitVelocityOperator) applied
  // to a velocity perturbation w against f_I(y + w) - f_I(y) (exact: f_I is linear in the
  // velocities). Away from the walls every row agrees to round-off for any w; next to them L
  // lumps the wall velocities' dependence on the fluid's (the no-slip mirror) onto the
  // diagonal, so there its rows agree for a uniform w (the row sums are exact) and differ for
  // a varying one.
  SceneHeader h;
  Config cfg = loadScene(VESPH_SOURCE_DIR "/cases/poiseuille_newtonian.toml", {"time.end=0.002", "output.times=[0.002]"}, h);
  Simulation<2> sim(cfg, h);
  REQUIRE(sim.run(RunOptions{"", true, false, 0}).status == RunStatus::ok);
  SphSystem<2>& sys = sim.system();
  const std::vector<double> y = sim.state();
  const StateSegments seg = sys.segments();
  const std::size_t n = sys.particles.n_moving;
  CsrMatrix L;
  REQUIRE(sys.implicitVelocityOperator(0.002, y.data(), L));
  REQUIRE(L.rows() == static_cast<int>(n));
  for (std::size_t i = 0; i < n; ++i) REQUIRE(L.column[static_cast<std::size_t>(L.row_start[i])] == static_cast<int>(i));
  const double support = sys.kernel.supportRadius();
  std::vector<char> near_wall(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t b = n; b < sys.particles.size(); ++b) {
      const double dx = sys.particles.position[2 * i] - sys.particles.position[2 * b];
      const double dy = sys.particles.position[2 * i + 1] - sys.particles.position[2 * b + 1];
      if (std::abs(dx) < 0.5 && dx * dx + dy * dy < support * support) near_wall[i] = 1;
    }
  std::vector<double> f0(y.size()), f1(y.size());
  sys.rhsPart(RhsPart::implicit_part, 0.002, y.data(), f0.data());
  for (const bool uniform : {false, true}) {
    std::vector<double> perturbed = y;
    for (std::size_t k = seg.velocity_begin; k < seg.velocity_end; ++k)
      perturbed[k] += uniform ? (k % 2 ? 2e-3 : -1e-3) : 1e-3 * std::sin(0.37 * static_cast<double>(k));
    sys.rhsPart(RhsPart::implicit_part, 0.002, perturbed.data(), f1.data());
    double interior_error = 0, wall_error = 0;
    std::size_t interior_rows = 0, wall_rows = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (int a = 0; a < 2; ++a) {
        double lw = 0, row_scale = 0;
        for (int k = L.row_start[i]; k < L.row_start[i + 1]; ++k) {
          const std::size_t c = seg.velocity_begin + 2 * static_cast<std::size_t>(L.column[k]) + static_cast<std::size_t>(a);
          const double term = L.value[k] * (perturbed[c] - y[c]);
          lw += term;
          row_scale = std::max(row_scale, std::abs(term));
        }
        const double jw = f1[seg.velocity_begin + 2 * i + a] - f0[seg.velocity_begin + 2 * i + a];
        double& error = near_wall[i] ? wall_error : interior_error;
        error = std::max(error, std::abs(lw - jw) / row_scale);
        (near_wall[i] ? wall_rows : interior_rows) += 1;
      }
    INFO("uniform " << uniform << ": interior rows " << interior_rows << ", error " << interior_error << "; wall rows "
                    << wall_rows << ", error " << wall_error);
    CHECK(interior_rows > n / 2);
    CHECK(wall_rows > n / 10);
    CHECK(interior_error < 1e-9);
    if (uniform) CHECK(wall_error < 1e-9);
    else CHECK(wall_error > 1e-3);
  }
}

namespace {

// A short start-up of a model's channel run twice, with the integrator settings `reference`
// and `tested` (scene overrides): the velocities and the evolving stresses (if any) at the end
// agree to `tolerance` of their largest value. One test case per model and integrator, so that
// ctest runs them side by side (the sanitizer build of tools/run-tests.sh takes minutes over
// them).
void checkModelRunsAgree(const std::string& scene, const std::string& end, const std::vector<std::string>& reference,
                         const std::vector<std::string>& tested, double tolerance) {
  CAPTURE(scene);
  auto runWith = [&](const std::vector<std::string>& integrator, std::uint64_t& steps) {
    std::vector<std::string> over = integrator;
    over.insert(over.end(), {"time.end=" + end, "output.times=[" + end + "]"});
    SceneHeader h;
    Config cfg = loadScene(std::string(VESPH_SOURCE_DIR "/cases/") + scene + ".toml", over, h);
    Simulation<2> sim(cfg, h);
    const RunReport r = sim.run(RunOptions{"", true, false, 0});
    REQUIRE(r.status == RunStatus::ok);
    steps = r.summary["steps"].get<std::uint64_t>();
    return std::make_pair(sim.state(), sim.system().segments());
  };
  std::uint64_t steps_reference = 0, steps_tested = 0;
  const auto [a, seg] = runWith(reference, steps_reference);
  const std::vector<double> b = runWith(tested, steps_tested).first;
  REQUIRE(a.size() == b.size());
  // velocities, then the evolving stresses (if any)
  const std::size_t bounds[] = {seg.velocity_begin, seg.velocity_end, a.size()};
  for (int s = 0; s < 2; ++s) {
    double scale = 0, diff = 0;
    for (std::size_t k = bounds[s]; k < bounds[s + 1]; ++k) {
      scale = std::max(scale, std::abs(a[k]));
      diff = std::max(diff, std::abs(a[k] - b[k]));
    }
    MESSAGE(scene << std::string(s ? " stresses" : " velocities") << ": max difference " << diff << " of " << scale
                  << "; steps " << steps_reference << " and " << steps_tested);
    CHECK(diff <= tolerance * scale);
  }
}

// The explicit adaptive 'arkode' against 'arkode-imex', both at rtol = 1e-6: agreement to 1e-5
// (measured: at most 4e-7, the UCM stresses).
void checkImexMatchesExplicit(const std::string& scene, const std::string& end) {
  checkModelRunsAgree(scene, end, {"integrator.type=\"arkode\"", "integrator.rtol=1e-6"},
                      {"integrator.type=\"arkode-imex\"", "integrator.rtol=1e-6"}, 1e-5);
}

// Every constitutive model under 'semi-implicit' against the leapfrog (itself within 5e-5 of
// an arkode run at rtol 1e-6 on these cases): agreement to 1e-3. Measured at the ends below
// (largest of velocities, stresses): Newtonian 3.6e-4, second-order fluid 2.3e-5, Oldroyd-B
// 1.9e-4, UCM 6e-5, XPP 1.5e-5 — the splitting's error in the wall layer (docs/theory.md §9.6).
void checkSemiImplicitMatchesLeapfrog(const std::string& scene, const std::string& end) {
  checkModelRunsAgree(scene, end, {"integrator.type=\"leapfrog\""}, {"integrator.type=\"semi-implicit\""}, 1e-3);
}

}  // namespace

TEST_CASE("integrators: arkode-imex matches an explicit run: Newtonian") {
  checkImexMatchesExplicit("poiseuille_newtonian", "0.05");
}
TEST_CASE("integrators: arkode-imex matches an explicit run: Newtonian with the stress form") {
  checkModelRunsAgree("poiseuille_newtonian", "0.05",
                      {"integrator.type=\"arkode\"", "integrator.rtol=1e-6", "effects.viscosity.form=\"stress\"",
                       "effects.velocity_gradient.form=\"renormalised\""},
                      {"integrator.type=\"arkode-imex\"", "integrator.rtol=1e-6", "effects.viscosity.form=\"stress\"",
                       "effects.velocity_gradient.form=\"renormalised\""},
                      1e-5);
}
TEST_CASE("integrators: arkode-imex matches an explicit run: second-order fluid") {
  // Explicit in both (only its viscous term is implicit), at the step of its stiff rate: 0.25 ms
  // is about 300 steps.
  checkImexMatchesExplicit("startup_channel_second_order_fluid", "0.00025");
}
TEST_CASE("integrators: arkode-imex matches an explicit run: Oldroyd-B") {
  checkImexMatchesExplicit("startup_channel_oldroyd_b", "0.05");
}
TEST_CASE("integrators: arkode-imex matches an explicit run: UCM") {
  checkImexMatchesExplicit("startup_channel_ucm", "0.05");
}
TEST_CASE("integrators: arkode-imex matches an explicit run: XPP") {
  checkImexMatchesExplicit("startup_channel_xpp", "0.05");
}

TEST_CASE("integrators: semi-implicit matches the leapfrog: Newtonian") {
  checkSemiImplicitMatchesLeapfrog("poiseuille_newtonian", "0.05");
}
TEST_CASE("integrators: semi-implicit matches the leapfrog: second-order fluid") {
  checkSemiImplicitMatchesLeapfrog("startup_channel_second_order_fluid", "0.00025");
}
TEST_CASE("integrators: semi-implicit matches the leapfrog: Oldroyd-B") {
  checkSemiImplicitMatchesLeapfrog("startup_channel_oldroyd_b", "0.05");
}
TEST_CASE("integrators: semi-implicit matches the leapfrog: UCM") {
  checkSemiImplicitMatchesLeapfrog("startup_channel_ucm", "0.05");
}
TEST_CASE("integrators: semi-implicit matches the leapfrog: XPP") {
  checkSemiImplicitMatchesLeapfrog("startup_channel_xpp", "0.05");
}
