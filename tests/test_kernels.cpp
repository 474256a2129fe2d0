// Smoothing kernels (vesph/core/kernel.hpp): normalisation, derivative, support, symmetry.
// Every kernel is checked in 2D and 3D against properties that hold for any correct SPH
// kernel, never against numbers produced by the code itself.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <random>
#include <string>

#include "vesph/core/kernel.hpp"
#include "vesph/core/types.hpp"

using namespace vesph;

namespace {

constexpr std::array<KernelType, 3> kAllKernels{KernelType::cubic, KernelType::quintic,
                                                KernelType::wendland_c2};

std::string label(KernelType t, int dim) {
  return std::string(kernelName(t)) + " " + std::to_string(dim) + "D";
}

// Calls fn(dx_vector[3], r) for every lattice point k*dx (k in Z^dim) with |k dx - x0| below
// reach; unused components are zero.
template <class Fn>
void forLattice(int dim, double dx, const double* x0, double reach, Fn&& fn) {
  const int n = static_cast<int>(std::ceil(reach / dx)) + 2;
  const int nz = dim == 3 ? n : 0;
  for (int a = -n; a <= n; ++a)
    for (int b = -n; b <= n; ++b)
      for (int c = -nz; c <= nz; ++c) {
        const double d[3] = {a * dx - x0[0], b * dx - x0[1], dim == 3 ? c * dx - x0[2] : 0.0};
        const double r = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (r < reach) fn(d, r);
      }
}

}  // namespace

TEST_CASE("kernels: radial integral of W is 1 (high-order quadrature)") {
  // int W dV = S_D int_0^R r^(D-1) W(r) dr with S_2 = 2 pi, S_3 = 4 pi. Composite Simpson on
  // 6000 intervals whose nodes include the profile's knots (q = 1, 2, 3 are multiples of
  // R/6000): each piece of the integrand is a polynomial of degree <= 7, so the error is
  // below ~1e-14; 1e-10 leaves room for rounding while any wrong normalisation constant
  // sigma_D (a typo changes it by far more than 1e-10) fails.
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3}) {
      CAPTURE(label(t, dim));
      const Kernel k(t, dim, 0.37);
      const double R = k.supportRadius();
      const int n = 6000;
      const double dr = R / n;
      double s = 0;
      for (int i = 0; i <= n; ++i) {
        const double r = i * dr;
        const double w = (i == 0 || i == n) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        s += w * std::pow(r, dim - 1) * k.W(r);
      }
      s *= dr / 3.0 * (dim == 2 ? 2.0 * M_PI : 4.0 * M_PI);
      CHECK(s == doctest::Approx(1.0).epsilon(1e-10));
    }
}

TEST_CASE("kernels: lattice sum of W dx^D is 1, on and off lattice") {
  // sum_k W(|k dx - x0|) dx^D is a quadrature of int W dV = 1 with the trapezoidal rule,
  // whose error for a smooth compactly supported integrand falls fast with h/dx. At
  // h = 16 dx the measured worst errors over the offsets below were 3.8e-8 (Wendland C2, 2D)
  // and 3.1e-8 (cubic, 2D), the others below 1e-8, so 1e-6 (the target accuracy) has a
  // margin of ~25 while a 0.1% error in a normalisation constant fails.
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double dx = 0.01, h = 16 * dx;
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3}) {
      CAPTURE(label(t, dim));
      const Kernel k(t, dim, h);
      std::vector<std::array<double, 3>> offsets = {{0, 0, 0}, {0.5 * dx, 0.5 * dx, 0.5 * dx}};
      for (int o = 0; o < 3; ++o) offsets.push_back({u(rng) * dx, u(rng) * dx, u(rng) * dx});
      for (const auto& x0 : offsets) {
        CAPTURE(x0[0] / dx);
        double s = 0;
        forLattice(dim, dx, x0.data(), k.supportRadius(), [&](const double*, double r) { s += k.W(r); });
        s *= std::pow(dx, dim);
        CHECK(std::abs(s - 1.0) < 1e-6);
      }
    }
}

TEST_CASE("kernels: latticeSum is the centred lattice sum, near 1/dx^D") {
  // Kernel::latticeSum(dx) (the number density of an undisturbed particle: the free-surface
  // threshold's reference and the ISPH density relaxation's target) against the test's own
  // lattice walk centred on a particle, and against 1/dx^D as h/dx grows (the quadrature
  // above: 1e-6 at h = 16 dx). At h = 1.6 dx, the cases' ratio, it is within a few per cent.
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3})
      for (double ratio : {1.3, 1.6, 16.0}) {
        CAPTURE(label(t, dim));
        CAPTURE(ratio);
        const double dx = 0.01;
        const Kernel k(t, dim, ratio * dx);
        const double x0[3] = {0, 0, 0};
        double s = 0;
        forLattice(dim, dx, x0, k.supportRadius(), [&](const double*, double r) { s += k.W(r); });
        CHECK(k.latticeSum(dx) == doctest::Approx(s).epsilon(1e-12));
        const double relative = k.latticeSum(dx) * std::pow(dx, dim);
        CHECK(std::abs(relative - 1.0) < (ratio > 10 ? 1e-6 : 0.05));
      }
}

TEST_CASE("kernels: dW/dr matches a central difference of W") {
  // Central difference with step e = 1e-5 h: truncation error e^2 |W'''|/6 ~ 1e-11 of the
  // scale sigma/h^(D+1), rounding ~ 1e-16 W/e ~ 1e-11 of it; W''' only jumps at the knots,
  // where the difference stays O(e^2). Measured worst: 2.6e-10 of max|dW/dr|. Tolerance 1e-8
  // of max|dW/dr| (the derivative itself vanishes at r = 0 and at the support, so a purely
  // relative test would be ill posed there); a wrong coefficient in f'(q) gives errors of
  // order 1e-2 or more.
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3}) {
      CAPTURE(label(t, dim));
      const double h = 0.023;
      const Kernel k(t, dim, h);
      const double R = k.supportRadius(), e = 1e-5 * h;
      double scale = 0;
      for (int i = 1; i < 1000; ++i) scale = std::max(scale, std::abs(k.dWdr(R * i / 1000.0)));
      REQUIRE(scale > 0);
      for (int i = 1; i < 997; ++i) {
        const double r = R * (i + 0.3) / 1000.0;  // avoids sitting exactly on a knot
        CAPTURE(r / h);
        const double fd = (k.W(r + e) - k.W(r - e)) / (2 * e);
        CHECK(std::abs(k.dWdr(r) - fd) < 1e-8 * scale);
      }
    }
}

TEST_CASE("kernels: W > 0 and dW/dr <= 0 inside the support, both zero at and beyond it") {
  // Exact properties of the profiles; the only rounding issue is r = support itself, where
  // q = (q_s h)/h can be one ulp below q_s: W is then of order ulp^3 relative to W(0), so the
  // check at r = support allows 1e-30 W(0) (anything physical is far larger).
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3})
      for (double h : {1.0, 0.1, 0.013, 3.7e-4}) {
        CAPTURE(label(t, dim));
        CAPTURE(h);
        const Kernel k(t, dim, h);
        const double R = k.supportRadius(), w0 = k.W(0.0);
        CHECK(w0 > 0);
        CHECK(k.dWdr(0.0) == 0.0);
        for (int i = 1; i < 1000; ++i) {
          const double r = R * i / 1000.0;
          CHECK(k.W(r) > 0);
          CHECK(k.dWdr(r) <= 0);
          CHECK(k.W(r) <= w0);
        }
        CHECK(std::abs(k.W(R)) <= 1e-30 * w0);
        CHECK(std::abs(k.dWdr(R)) <= 1e-30 * w0 / h);
        for (double f : {1.0 + 1e-12, 1.001, 1.5, 10.0}) {
          CHECK(k.W(R * f) == 0.0);
          CHECK(k.dWdr(R * f) == 0.0);
        }
      }
}

TEST_CASE("kernels: the kernel gradient sums to zero over a symmetric lattice") {
  // grad_i W_ij = F r_ij with F = (dW/dr)/r. Around a lattice point the lattice is symmetric
  // under x -> -x, so sum_j F r_ij dx^D cancels pairwise: only rounding remains, compared
  // with sum_j |F r_ij| dx^D (~1/h) at 1e-13. Off the lattice the sum is a quadrature of
  // int grad W dV = 0 (trapezoidal error, as for the normalisation): with h = 16 dx the
  // measured h * |sum| was at most 1.7e-6 (Wendland C2 and cubic in 2D, the C2 kernels; the
  // quintic gave 2e-10), so 1e-5 leaves a margin of ~6.
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (KernelType t : kAllKernels)
    for (int dim : {2, 3}) {
      CAPTURE(label(t, dim));
      for (double hdx : {1.3, 1.6, 2.0, 16.0}) {
        CAPTURE(hdx);
        const double dx = 0.01, h = hdx * dx;
        const Kernel k(t, dim, h);
        const double zero[3] = {0, 0, 0};
        double g[3] = {0, 0, 0}, mag = 0;
        forLattice(dim, dx, zero, k.supportRadius(), [&](const double* d, double r) {
          if (r == 0) return;
          const double F = k.dWdr(r) / r;
          // r_ij = x_i - x_j = x0 - (lattice point) = -d
          for (int a = 0; a < 3; ++a) g[a] += -F * d[a];
          mag += std::abs(F) * r;
        });
        for (int a = 0; a < dim; ++a) CHECK(std::abs(g[a]) <= 1e-13 * mag);
        if (hdx == 16.0) {
          const double x0[3] = {u(rng) * dx, u(rng) * dx, u(rng) * dx};
          double go[3] = {0, 0, 0};
          forLattice(dim, dx, x0, k.supportRadius(), [&](const double* d, double r) {
            if (r == 0) return;
            const double F = k.dWdr(r) / r;
            for (int a = 0; a < 3; ++a) go[a] += -F * d[a] * std::pow(dx, dim);
          });
          for (int a = 0; a < dim; ++a) CHECK(h * std::abs(go[a]) < 1e-5);
        }
      }
    }
}

TEST_CASE("kernels: names round-trip and unknown names are rejected") {
  for (KernelType t : kAllKernels) CHECK(kernelFromName(kernelName(t)) == t);
  CHECK(kernelNames().size() == kAllKernels.size());
  for (const std::string& n : kernelNames()) CHECK_NOTHROW(kernelFromName(n));
  CHECK_THROWS_AS(kernelFromName("gaussian"), InputError);
  CHECK_THROWS_AS(kernelFromName(""), InputError);
  CHECK_THROWS_AS(kernelFromName("quintic "), InputError);
  CHECK_THROWS_AS(Kernel(KernelType::cubic, 2, 0.0), InputError);
  CHECK_THROWS_AS(Kernel(KernelType::cubic, 2, -1.0), InputError);
}
