// The Newtonian viscous force (src/physics/viscosity.cpp) in its two forms: Morris' Laplacian
// (thesis eq. 3.37, form = "laplacian", the default) and the stress form (form = "stress":
// tau = mu (kappa + kappa^T) and its symmetric divergence, thesis eq. 3.18, between fluid
// particles; docs/theory.md §5.4). Each runs inside a real SphSystem built by hand
// (tests/hand_built_system.hpp), with only
// [effects.equation_of_state] beside it (pressure, no force) and, for the stress form,
// [effects.velocity_gradient], so dv/dt is the viscous force alone.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <utility>

#include "hand_built_system.hpp"

using namespace vesph;

namespace {

using testing::Box;
using testing::kRho0;
constexpr double kMu = 2.0;  // Pa s

// A lattice or disk of fluid particles of spacing dx (quintic kernel, h = 1.6 dx) with the
// viscosity kMu, evaluated once.
std::unique_ptr<Box<2>> build(const std::string& effects, double dx, double length, bool periodic,
                              const std::vector<std::pair<Vec<2>, Vec<2>>>& particles) {
  auto b = std::make_unique<Box<2>>(effects, dx, 1.6, KernelType::quintic, length, periodic);
  b->viscosity = kMu;
  for (const auto& [x, v] : particles) b->add(x, v, kRho0, b->mass());
  b->finish();
  b->evaluate();
  return b;
}

const std::string kLaplacian = "[effects.viscosity]\n";
const std::string kStress = "[effects.velocity_gradient]\n[effects.viscosity]\nform = \"stress\"\n";
const std::string kStressRenormalised =
    "[effects.velocity_gradient]\nform = \"renormalised\"\n[effects.viscosity]\nform = \"stress\"\n";

}  // namespace

TEST_CASE("viscosity: both forms give mu lap v of a shear wave inside a periodic lattice, to second order") {
  // v = (U sin(k y), 0): divergence-free, mu lap v = -mu k^2 v, and div(mu (grad v + grad v^T))
  // is the same. One wavelength across 40 and 80 particles (k h = 0.25 and 0.126). The stress
  // form's second part, div(mu kappa^T) = mu grad(div v), is zero here; both fall as (k h)^2.
  const double L = 1.0, U = 1e-3, k = 2 * std::numbers::pi / L;
  auto worstError = [&](const std::string& form, int n) {
    const double dx = L / n;
    std::vector<std::pair<Vec<2>, Vec<2>>> lattice;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx);
        lattice.emplace_back(x, Vec<2>(U * std::sin(k * x[1]), 0.0));
      }
    const auto box = build(form, dx, L, true, lattice);
    const Box<2>& b = *box;
    const double scale = kMu / kRho0 * k * k * U;
    double worst = 0;
    for (std::size_t i = 0; i < b.n(); ++i) {
      const double yi = b.sys.particles.position[2 * i + 1];
      const Vec<2> exact(-scale * std::sin(k * yi), 0.0);
      worst = std::max(worst, (b.dvdt(i) - exact).norm() / scale);
    }
    return worst;
  };
  const double lap40 = worstError(kLaplacian, 40), lap80 = worstError(kLaplacian, 80);
  const double str40 = worstError(kStress, 40), str80 = worstError(kStress, 80);
  MESSAGE("relative error at 40 / 80 across: laplacian " << lap40 << " / " << lap80 << ", stress " << str40 << " / "
                                                          << str80);
  CHECK(lap40 < 0.01);
  CHECK(str40 < 0.01);
  CHECK(str80 < str40 / 3.0);  // second order: 4x for the halved spacing (3.3 measured)
  CHECK(lap80 < lap40 / 3.0);
}

TEST_CASE("viscosity: a rigidly turning disk with a free surface: no force in the stress form, a drag in the Laplacian") {
  // A fluid disk (radius 10 dx, free surface all round) turning rigidly at Omega: its strain
  // rate is zero, so the stress-free surface condition holds and the exact viscous force is
  // zero everywhere. The Laplacian's natural surface condition is dv/dn = 0, which a rotation
  // violates: its missing outer neighbours brake the surface rows by about nu Omega R / h. The
  // stress form with the renormalised gradient (exact for linear fields) gives zero to
  // round-off; with the standard gradient, whose kernel moments the surface cuts, the two
  // boundary terms cancel only in part (0.37 of the Laplacian's drag, measured).
  const double dx = 0.01, R = 10 * dx, Omega = 0.5;
  std::vector<std::pair<Vec<2>, Vec<2>>> disk;
  for (int i = -12; i <= 12; ++i)
    for (int j = -12; j <= 12; ++j) {
      const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx);
      if (x.norm() < R) disk.emplace_back(x, Vec<2>(-Omega * x[1], Omega * x[0]));
    }
  const double scale = kMu / kRho0 * Omega * R / (1.6 * dx * 1.6 * dx);  // nu Omega R / h^2
  auto worst = [&](const Box<2>& b) {
    double w = 0;
    for (std::size_t i = 0; i < b.n(); ++i) w = std::max(w, b.dvdt(i).norm());
    return w / scale;
  };
  const auto laplacian = build(kLaplacian, dx, 2 * R, false, disk);
  const auto stress = build(kStress, dx, 2 * R, false, disk);
  const auto renormalised = build(kStressRenormalised, dx, 2 * R, false, disk);
  MESSAGE("largest |dv/dt| / (nu Omega R / h^2): laplacian " << worst(*laplacian) << ", stress " << worst(*stress)
                                                             << ", stress renormalised " << worst(*renormalised));
  CHECK(worst(*laplacian) > 0.05);
  CHECK(worst(*renormalised) < 1e-10);
  CHECK(worst(*stress) < 0.5 * worst(*laplacian));
  // The Laplacian brakes the rotation: the torque about the centre opposes Omega.
  double torque = 0;
  for (std::size_t i = 0; i < laplacian->n(); ++i) {
    const Vec<2> x = laplacian->sys.particles.x(i);
    const Vec<2> a = laplacian->dvdt(i);
    torque += x[0] * a[1] - x[1] * a[0];
  }
  CHECK(torque < 0);
}

TEST_CASE("viscosity: fluid turning rigidly with a turning rod: wall_stress = continued removes the stress form's drag") {
  // A fluid annulus 4 dx < r < 20 dx on a square lattice turning rigidly at Omega about a rod
  // (the lattice points r < 4 dx, wall particles that carry the same rigid velocity): the exact
  // viscous force is zero. Inside the fluid, away from the outer free surface (r < 10 dx: whole
  // supports of fluid and wall, and of every neighbour's kappa), the lattice's symmetry makes both forms zero to round-off, but
  // the stress form only if the wall particles enter both its sums (wall_stress = "continued"):
  // left out of the divergence of mu kappa^T (the default, "omitted"), the rod acts as a free
  // surface for that part and the missing neighbours put the traction mu kappa^T.n on the first
  // rings (for a rotation kappa^T.n = -Omega x n: a drag beside a turning rod, docs/theory.md
  // §5.4; 0.084 nu Omega R/h^2 here, measured).
  const double dx = 0.01, a = 4 * dx, R = 20 * dx, Omega = 0.5;
  auto run = [&](const std::string& effects) {
    auto b = std::make_unique<Box<2>>(effects, dx, 1.6, KernelType::quintic, 2 * R, false);
    b->viscosity = kMu;
    b->annulusAroundRod(a, R, [&](const Vec<2>& x) { return Vec<2>(-Omega * x[1], Omega * x[0]); });
    b->finish();
    b->evaluate();
    const double scale = kMu / kRho0 * Omega * R / (1.6 * dx * 1.6 * dx);  // nu Omega R / h^2
    double worst = 0;
    for (std::size_t i = 0; i < b->n(); ++i)
      if (b->sys.particles.x(i).norm() < 10 * dx) worst = std::max(worst, b->dvdt(i).norm() / scale);
    return worst;
  };
  const std::string continued = "wall_stress = \"continued\"\n";
  const double laplacian = run(kLaplacian), omitted = run(kStress), stress = run(kStress + continued),
               renormalised = run(kStressRenormalised + continued);
  MESSAGE("largest |dv/dt| / (nu Omega R / h^2) for r < 10 dx: laplacian " << laplacian << ", stress (walls omitted) "
                                                                          << omitted << ", stress (continued) " << stress
                                                                          << ", stress renormalised (continued) "
                                                                          << renormalised);
  CHECK(laplacian < 1e-10);
  CHECK(omitted > 0.05);
  CHECK(stress < 1e-10);
  CHECK(renormalised < 1e-10);
}

TEST_CASE("viscosity: wall_stress = continued_where_full is continued in a full kernel, omitted where a surface cuts it") {
  // The rigidly turning fluid around a turning rod of the test above. "continued_where_full"
  // scales the continued wall terms by f = clamp((S - 0.85)/0.12, 0, 1), S = sum_j V_j W_ij over
  // fluid, walls and the particle itself. (1) In the wide annulus (R = 20 dx) every particle at
  // r < 10 dx has a full lattice kernel (S = 1), so f = 1 and the rotation gives no force, as
  // with "continued" (the default "omitted" leaves a drag there). (2) In a film two rows thick
  // (R = 6 dx) the outer free surface cuts every kernel: each particle's force is
  // omitted + f(S) (continued - omitted), with S summed here by brute force, and where S < 0.85
  // next to the rod the wall term is absent (the result is "omitted"'s). Both parts need the
  // kernel value W in the viscosity's pair pass (needsKernelValue): without it S is the self
  // term alone and f = 0 everywhere.
  const double dx = 0.01, a = 4 * dx, Omega = 0.5;
  const double scale = kMu / kRho0 * Omega * 20 * dx / (1.6 * dx * 1.6 * dx);  // nu Omega R / h^2, R = 20 dx
  auto build = [&](const std::string& effects, double R) {
    auto b = std::make_unique<Box<2>>(effects, dx, 1.6, KernelType::quintic, 2 * R, false);
    b->viscosity = kMu;
    b->annulusAroundRod(a, R, [&](const Vec<2>& x) { return Vec<2>(-Omega * x[1], Omega * x[0]); });
    b->finish();
    b->evaluate();
    return b;
  };
  const std::string continued = kStress + "wall_stress = \"continued\"\n";
  const std::string where_full = kStress + "wall_stress = \"continued_where_full\"\n";

  // (1) The full kernels beside the rod.
  {
    const auto omitted = build(kStress, 20 * dx), blended = build(where_full, 20 * dx);
    double worst_omitted = 0, worst_blended = 0;
    for (std::size_t i = 0; i < blended->n(); ++i)
      if (blended->sys.particles.x(i).norm() < 10 * dx) {
        worst_omitted = std::max(worst_omitted, omitted->dvdt(i).norm() / scale);
        worst_blended = std::max(worst_blended, blended->dvdt(i).norm() / scale);
      }
    MESSAGE("largest |dv/dt| / (nu Omega R / h^2) for r < 10 dx: omitted " << worst_omitted
                                                                          << ", continued_where_full " << worst_blended);
    CHECK(worst_omitted > 0.05);
    CHECK(worst_blended < 1e-10);
  }

  // (2) The film on the rod: every kernel cut by the free surface (S from 0.55 to 0.91 measured).
  const auto omitted = build(kStress, 6 * dx), full = build(continued, 6 * dx), blended = build(where_full, 6 * dx);
  const ParticleSet<2>& p = blended->sys.particles;
  const Kernel& kernel = blended->sys.kernel;
  int cut_beside_wall = 0, partial = 0, mismatched = 0;
  double smallest = 1e300, largest = 0;
  for (std::size_t i = 0; i < blended->n(); ++i) {
    double S = 0;
    bool wall_neighbour = false;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const double r = (p.x(i) - p.x(j)).norm();
      if (r >= kernel.supportRadius()) continue;
      S += p.mass[j] / p.density[j] * kernel.W(r);
      wall_neighbour = wall_neighbour || j >= p.n_moving;
    }
    smallest = std::min(smallest, S);
    largest = std::max(largest, S);
    const double f = std::clamp((S - 0.85) / 0.12, 0.0, 1.0);
    const Vec<2> wall_term = full->dvdt(i) - omitted->dvdt(i);
    const Vec<2> expected = omitted->dvdt(i) + f * wall_term;
    if ((blended->dvdt(i) - expected).norm() > 1e-9 * scale) ++mismatched;
    if (wall_neighbour && S < 0.85) {
      CHECK((blended->dvdt(i) - omitted->dvdt(i)).norm() < 1e-12 * scale);
      if (wall_term.norm() > 0.01 * scale) ++cut_beside_wall;  // a wall term there to leave out
    }
    if (wall_neighbour && f > 0 && f < 1) ++partial;
  }
  MESSAGE("film on the rod: S from " << smallest << " to " << largest << ", " << cut_beside_wall
                                    << " particles with S < 0.85 and a wall term over 0.01 nu Omega R / h^2, " << partial << " blended in part");
  CHECK(mismatched == 0);
  CHECK(cut_beside_wall >= 8);
  CHECK(partial >= 4);  // and some rows take the continuation in part (0.85 < S < 0.97)
}

TEST_CASE("viscosity: form keys are checked") {
  auto setupOf = [](const std::string& effects) {
    build(effects, 0.1, 1.0, false, {{Vec<2>(0.0, 0.0), Vec<2>::Zero()}, {Vec<2>(0.1, 0.0), Vec<2>::Zero()}});
  };
  CHECK_THROWS_WITH_AS(setupOf("[effects.viscosity]\nform = \"stress\"\n"),
                       doctest::Contains("needs the velocity gradient: add [effects.velocity_gradient]"), InputError);
  CHECK_THROWS_WITH_AS(setupOf("[effects.viscosity]\nwall_stress = \"continued\"\n"),
                       doctest::Contains("applies to the stress form"), InputError);
  CHECK_THROWS_WITH_AS(setupOf(kStress + "wall_stress = \"mirrored\"\n"), doctest::Contains("omitted, continued, continued_where_full"),
                       InputError);
  CHECK_THROWS_WITH_AS(setupOf("[effects.viscosity]\nform = \"tensor\"\n"), doctest::Contains("laplacian, stress"),
                       InputError);
}
