// A hand-built SphSystem for unit tests of single effects (tests/test_stabilisers.cpp,
// tests/test_viscosity.cpp): add particles (moving first), then finish() and evaluate(), with
// [effects.equation_of_state] beside the effects under test (pressure and sound speed, no force).
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "vesph/physics/registry.hpp"
#include "vesph/sim/system.hpp"

namespace vesph::testing {

constexpr double kRho0 = 1000.0;
constexpr double kSound = 10.0;  // m/s

template <int D>
struct Box {
  Config cfg;
  SphSystem<D> sys;
  double dx;
  double viscosity = 0.0;  // fluid.viscosity mu handed to the effects' setup, Pa s
  std::vector<double> y, ydot;

  Box(const std::string& effects, double dx_, double h_over_dx, KernelType kt, double length, bool periodic)
      : cfg(Config::fromString("[effects.equation_of_state]\nsound_speed = " + std::to_string(kSound) + "\n" + effects,
                               "test")),
        dx(dx_) {
    sys.kernel = Kernel(kt, D, h_over_dx * dx);
    sys.domain.lo = Vec<D>::Constant(periodic ? 0.0 : -length);
    sys.domain.hi = Vec<D>::Constant(length);
    for (int a = 0; a < D; ++a) sys.domain.periodic[a] = periodic;
  }
  double mass() const { return kRho0 * std::pow(dx, D); }
  void add(const Vec<D>& x, const Vec<D>& v, double rho, double m, bool fixed = false) {
    sys.particles.add(x, v, rho, m, fixed ? ParticleKind::wall : ParticleKind::fluid, sys.particles.size());
    if (!fixed) sys.particles.n_moving = sys.particles.size();
  }
  // n^D lattice of spacing dx from the origin (cell centres), all moving, with velocity v(x).
  template <class Fn>
  void lattice(int n, Fn&& velocity) {
    std::size_t total = 1;
    for (int a = 0; a < D; ++a) total *= static_cast<std::size_t>(n);
    for (std::size_t c = 0; c < total; ++c) {
      std::size_t rem = c;
      Vec<D> x;
      for (int a = 0; a < D; ++a) {
        x[a] = (static_cast<int>(rem % n) + 0.5) * dx;
        rem /= n;
      }
      add(x, velocity(x), kRho0, mass());
    }
  }
  // A fluid annulus a <= r < R on the square lattice of spacing dx about the origin (cell
  // centres), around a rod of wall particles on the lattice points r < a (2D); each particle
  // with the velocity v(x). The fluid first, in lattice order, then the rod.
  template <class Fn>
  void annulusAroundRod(double a, double R, Fn&& velocity) {
    static_assert(D == 2, "a 2D lattice");
    const int n = static_cast<int>(std::ceil(R / dx)) + 1;
    std::vector<Vec<D>> rod;
    for (int i = -n; i < n; ++i)
      for (int j = -n; j < n; ++j) {
        const Vec<D> x((i + 0.5) * dx, (j + 0.5) * dx);
        if (x.norm() < a) rod.push_back(x);
        else if (x.norm() < R) add(x, velocity(x), kRho0, mass());
      }
    for (const Vec<D>& x : rod) add(x, velocity(x), kRho0, mass(), true);
  }
  void finish(std::vector<std::unique_ptr<Effect<D>>> extra = {}) {
    ConfigTable root = cfg.root();
    ConfigTable eff = root.table("effects");
    sys.effects = makeEffects<D>(eff);
    for (auto& e : extra) sys.effects.push_back(std::move(e));
    cfg.rejectUnknownKeys();
    sys.setup(dx, kRho0, viscosity, 0.1 * sys.kernel.supportRadius());
    y.assign(sys.size(), 0.0);
    ydot.assign(sys.size(), 0.0);
    sys.pack(y.data());
  }
  void evaluate() {
    sys.pack(y.data());
    sys.evaluate(0.0, y.data(), ydot.data());
  }
  std::size_t n() const { return sys.particles.n_moving; }
  Vec<D> dxdt(std::size_t i) const { return Eigen::Map<const Vec<D>>(ydot.data() + D * i); }
  Vec<D> dvdt(std::size_t i) const { return Eigen::Map<const Vec<D>>(ydot.data() + n() * (D + 1) + D * i); }
};

}  // namespace vesph::testing
