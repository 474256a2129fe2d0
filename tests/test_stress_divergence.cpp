// The elastic force of src/physics/stress_divergence.cpp (Fang et al. 2006 eq. 27) and its
// wall_stress key: "extrapolated" (a wall neighbour enters with its own S, Fang eq. 46) or
// "continued" (with the fluid particle's S_i; docs/theory.md §5.6). Each runs inside a real
// SphSystem built by hand (tests/hand_built_system.hpp) with an Oldroyd-B fluid at rest, so
// dv/dt is the elastic force alone.
#include <doctest/doctest.h>

#include <algorithm>
#include <memory>
#include <string>

#include "hand_built_system.hpp"
#include "vesph/physics/constitutive.hpp"

using namespace vesph;
using testing::Box;
using testing::kRho0;

namespace {

// A fluid annulus 4 dx < r < 20 dx on a square lattice around a rod of wall particles (the
// lattice points r < 4 dx), at rest, with the uniform elastic stress S0 in the fluid and the
// value S_wall stored on the rod (no wall treatment runs here: the walls keep it). Returns the
// largest |dv/dt| over the fluid particles whose kernel the rod cuts (r < 7 dx), over |S0|/(rho h).
double worstForceBesideRod(const std::string& wall_stress, const Mat<2>& S0, const Mat<2>& S_wall) {
  const double dx = 0.01, a = 4 * dx, R = 20 * dx;
  Box<2> b("[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.1\npolymer_viscosity = 1.0\n"
           "[effects.stress_divergence]\nwall_stress = \"" + wall_stress + "\"\n",
           dx, 1.6, KernelType::quintic, 2 * R, false);
  b.annulusAroundRod(a, R, [](const Vec<2>&) { return Vec<2>::Zero(); });
  b.finish();
  Field* S = b.sys.particles.fields.find("elastic_stress");
  REQUIRE(S != nullptr);
  for (std::size_t i = 0; i < b.sys.particles.size(); ++i)
    packSymmetric<2>(i < b.n() ? S0 : S_wall, S->data.data() + static_cast<std::size_t>(S->components) * i);
  b.evaluate();
  double worst = 0;
  for (std::size_t i = 0; i < b.n(); ++i)
    if (b.sys.particles.x(i).norm() < 7 * dx) worst = std::max(worst, b.dvdt(i).norm());
  return worst / (S0.norm() / (kRho0 * 1.6 * dx));
}

}  // namespace

TEST_CASE("stress divergence: wall_stress = continued puts no force from the wall's values beside a rod") {
  // A uniform S has no divergence. With "continued" the wall terms are 2 S_i sum_j m_j grad W_ij
  // together with the fluid's, which the whole lattice makes zero, whatever the wall stores; with
  // "extrapolated" the wall's own values enter (here zero: the rod acts as a free surface for
  // the elastic force, a force of order |S|/(rho h) on the first rings), and the same uniform
  // value on the wall gives zero too.
  Mat<2> S0;
  S0 << 3.0, 1.5, 1.5, -0.5;  // Pa
  const double continued = worstForceBesideRod("continued", S0, Mat<2>::Zero());
  const double extrapolated_zero = worstForceBesideRod("extrapolated", S0, Mat<2>::Zero());
  const double extrapolated_same = worstForceBesideRod("extrapolated", S0, S0);
  MESSAGE("largest |dv/dt| / (|S|/(rho h)) beside the rod: continued " << continued << ", extrapolated with S = 0 on the wall "
                                                                     << extrapolated_zero << ", with S0 on the wall "
                                                                     << extrapolated_same);
  CHECK(continued < 1e-12);
  CHECK(extrapolated_same < 1e-12);
  CHECK(extrapolated_zero > 0.1);
}

TEST_CASE("stress divergence: wall_stress is checked") {
  CHECK_THROWS_WITH_AS(worstForceBesideRod("mirrored", Mat<2>::Identity(), Mat<2>::Zero()),
                       doctest::Contains("extrapolated, continued"), InputError);
}
