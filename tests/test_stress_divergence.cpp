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

namespace {

// The fluid annulus around the rod of the tests above, now with a sheared, turning velocity
// field (the rod's particles carry it too) and the elastic stress S = eta_p (kappa + kappa^T) of
// each fluid particle's own velocity gradient less its trace, eta_p (div v) I (the viscous stress
// the split takes out: Oldroyd-B's stress in the limit Wi -> 0 but for that isotropic part). Returns
// dv/dt of every fluid particle for the given effects (the Newtonian reference runs
// [effects.viscosity] with mu = eta_p instead).
std::vector<Vec<2>> forcesOfViscousStress(const std::string& effects, double mu) {
  const double dx = 0.01, a = 4 * dx, R = 14 * dx, eta_p = 0.7;
  Box<2> b(effects, dx, 1.6, KernelType::quintic, 2 * R, false);
  b.viscosity = mu;
  b.annulusAroundRod(a, R, [](const Vec<2>& x) {
    return Vec<2>(-3.0 * x[1] + 40.0 * x[0] * x[1], 2.0 * x[0] + 25.0 * x[1] * x[1] - 10.0 * x[0] * x[0]);
  });
  b.finish();
  if (Field* S = b.sys.particles.fields.find("elastic_stress")) {
    b.evaluate();  // the velocity gradient of these velocities
    const Field* kappa = b.sys.particles.fields.find("velocity_gradient");
    REQUIRE(kappa != nullptr);
    for (std::size_t i = 0; i < b.n(); ++i) {
      const Eigen::Map<const Eigen::Matrix<double, 2, 2, Eigen::RowMajor>> k(kappa->data.data() + 4 * i);
      const Mat<2> viscous = eta_p * (k + k.transpose() - k.trace() * Mat<2>::Identity());
      packSymmetric<2>(viscous, S->data.data() + static_cast<std::size_t>(S->components) * i);
    }
  }
  b.evaluate();
  std::vector<Vec<2>> f(b.n());
  for (std::size_t i = 0; i < b.n(); ++i) f[i] = b.dvdt(i);
  return f;
}

std::string oldroydB(const std::string& stress_divergence) {
  return "[effects.velocity_gradient]\n[effects.oldroyd_b]\nrelaxation_time = 0.1\npolymer_viscosity = 0.7\n"
         "[effects.stress_divergence]\nwall_stress = \"continued\"\n" + stress_divergence;
}

}  // namespace

TEST_CASE("stress divergence: the symmetric split moves the viscous part of S to Morris' Laplacian") {
  // With S = eta_p (kappa + kappa^T - tr(kappa) I) the symmetric split leaves S' = 0 on every fluid particle and, with the
  // walls continued, on every wall neighbour: both_sides_diffusion = 1 must give exactly the
  // Laplacian of viscosity eta_p (the viscous force's, walls presenting their velocity), on the
  // rod's rings and at the free surface alike, where eq. 27 alone differs from it (the two
  // discretisations part there: docs/theory.md §5.6). Half the split is the mean of the two.
  const auto laplacian = forcesOfViscousStress("[effects.viscosity]\n", 0.7);
  const auto eq27 = forcesOfViscousStress(oldroydB(""), 0.0);
  const auto whole = forcesOfViscousStress(oldroydB("both_sides_diffusion = 1\nboth_sides_form = \"symmetric\"\n"), 0.0);
  const auto half = forcesOfViscousStress(oldroydB("both_sides_diffusion = 0.5\nboth_sides_form = \"symmetric\"\n"), 0.0);
  REQUIRE(laplacian.size() == whole.size());
  double scale = 0, whole_error = 0, half_error = 0, forms_apart = 0;
  for (std::size_t i = 0; i < laplacian.size(); ++i) scale = std::max(scale, laplacian[i].norm());
  for (std::size_t i = 0; i < laplacian.size(); ++i) {
    whole_error = std::max(whole_error, (whole[i] - laplacian[i]).norm() / scale);
    half_error = std::max(half_error, (half[i] - 0.5 * (laplacian[i] + eq27[i])).norm() / scale);
    forms_apart = std::max(forms_apart, (eq27[i] - laplacian[i]).norm() / scale);
  }
  MESSAGE("largest |dv/dt - reference| / max |Laplacian|: split 1 " << whole_error << ", split 0.5 " << half_error
                                                                     << "; eq. 27 against the Laplacian " << forms_apart);
  CHECK(whole_error < 1e-12);
  CHECK(half_error < 1e-12);
  CHECK(forms_apart > 0.05);
}

TEST_CASE("stress divergence: the gradient split keeps a free surface stress-free; the symmetric one does not") {
  // A fluid disk (radius 10 dx, free surface all round) turning rigidly at Omega with no elastic
  // stress: the exact force is zero. The gradient split is eta_p (lap v - div kappa), and for a
  // rotation (kappa^T = -kappa) -div kappa = div kappa^T: the viscous force's stress form, which
  // with the renormalised gradient is zero to round-off on this disk (test_viscosity.cpp). The
  // symmetric split takes out eta_p (kappa + kappa^T - tr(kappa) I) = 0 and leaves the Laplacian,
  // whose natural surface condition dv/dn = 0 brakes the rotation at the surface.
  const double dx = 0.01, R = 10 * dx, Omega = 0.5, eta_p = 0.7;
  auto worst = [&](const std::string& form) {
    Box<2> b("[effects.velocity_gradient]\nform = \"renormalised\"\n[effects.oldroyd_b]\nrelaxation_time = 0.1\n"
             "polymer_viscosity = 0.7\n[effects.stress_divergence]\nboth_sides_diffusion = 1\nboth_sides_form = \"" +
                 form + "\"\n",
             dx, 1.6, KernelType::quintic, 2 * R, false);
    for (int i = -12; i <= 12; ++i)
      for (int j = -12; j <= 12; ++j) {
        const Vec<2> x((i + 0.5) * dx, (j + 0.5) * dx);
        if (x.norm() < R) b.add(x, Vec<2>(-Omega * x[1], Omega * x[0]), kRho0, b.mass());
      }
    b.finish();
    b.evaluate();
    double w = 0;
    for (std::size_t i = 0; i < b.n(); ++i) w = std::max(w, b.dvdt(i).norm());
    return w / (eta_p / kRho0 * Omega * R / (1.6 * dx * 1.6 * dx));  // over nu_p Omega R / h^2
  };
  const double gradient = worst("gradient"), symmetric = worst("symmetric");
  MESSAGE("largest |dv/dt| / (nu_p Omega R / h^2) on the turning disk: gradient split " << gradient
                                                                                       << ", symmetric split " << symmetric);
  CHECK(gradient < 1e-10);
  CHECK(symmetric > 0.05);
}

TEST_CASE("stress divergence: both_sides_diffusion is checked") {
  CHECK_THROWS_WITH_AS(forcesOfViscousStress(oldroydB("both_sides_diffusion = -1\n"), 0.0), doctest::Contains("non-negative"),
                       InputError);
  // A stress without a polymer viscosity to split: the second-order fluid's.
  CHECK_THROWS_WITH_AS(forcesOfViscousStress("[effects.velocity_gradient]\n[effects.viscosity]\n[effects.second_order_fluid]\n"
                                             "alpha1 = -1e-3\nalpha2 = 1e-4\n[effects.stress_divergence]\n"
                                             "both_sides_diffusion = 1\n",
                                             0.7),
                       doctest::Contains("rate-type model"), InputError);
  CHECK_THROWS_WITH_AS(forcesOfViscousStress(oldroydB("both_sides_form = \"gradient\"\n"), 0.0),
                       doctest::Contains("both_sides_diffusion > 0"), InputError);
  CHECK_THROWS_WITH_AS(forcesOfViscousStress(oldroydB("both_sides_diffusion = 1\nboth_sides_form = \"full\"\n"), 0.0),
                       doctest::Contains("gradient, symmetric"), InputError);
}
