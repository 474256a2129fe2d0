#pragma once
// A test harness shared by the constitutive tests (test_xpp.cpp, test_constitutive.cpp): one
// particle carrying the effects of a scene's [effects] text, as the solver runs them.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "vesph/physics/registry.hpp"
#include "vesph/sim/simulation.hpp"

namespace vesph::test_support {

// One particle carrying a constitutive effect built from the registry, as the solver runs it:
// rates() returns the rates of its evolving fields for a given velocity gradient and state.
template <int D>
struct OneParticle {
  Config cfg;
  ParticleSet<D> particles;
  Kernel kernel{KernelType::quintic, D, 1.0};
  Domain<D> domain;
  std::vector<Field*> evolving;
  std::vector<std::unique_ptr<Effect<D>>> effects;

  explicit OneParticle(const std::string& effect_toml)
      : cfg(Config::fromString("[effects.velocity_gradient]\n" + effect_toml, "test")) {
    particles.add(Vec<D>::Zero(), Vec<D>::Zero(), 1000.0, 1.0, ParticleKind::fluid, 0);
    particles.n_moving = 1;
    particles.fields.require("velocity_gradient", D * D);
    ConfigTable root = cfg.root();
    ConfigTable eff = root.table("effects");
    effects = makeEffects<D>(eff);
    Setup<D> s{particles, kernel, 1.0, 1000.0, 0.0, Vec<D>::Zero(), nullptr, &evolving};
    for (auto& e : effects)
      if (e->phase() == Phase::rates) e->setup(s);
    particles.resizeFields();
  }
  std::size_t size() const {
    std::size_t n = 0;
    for (const Field* f : evolving) n += f->components;
    return n;
  }
  Eigen::VectorXd rates(const Mat<D>& kappa, const Eigen::VectorXd& y) {
    Field* k = particles.fields.find("velocity_gradient");
    for (int a = 0; a < D; ++a)
      for (int b = 0; b < D; ++b) k->data[D * a + b] = kappa(a, b);
    std::size_t off = 0;
    for (Field* f : evolving)
      for (int c = 0; c < f->components; ++c) f->data[c] = y[off++];
    Eigen::VectorXd out = Eigen::VectorXd::Zero(y.size());
    std::vector<double*> slots;
    off = 0;
    for (Field* f : evolving) {
      slots.push_back(out.data() + off);
      off += f->components;
    }
    double dx[D], drho[1], dv[D];
    const RhsContext<D> ctx{particles, kernel, domain, 0.0, dx, drho, dv, slots.data()};
    for (auto& e : effects)
      if (e->phase() == Phase::rates) e->particles(ctx, 0, 1);
    return out;
  }
};


}  // namespace vesph::test_support
