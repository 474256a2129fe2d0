// Reference SPH operators (vesph/core/operators.hpp) on regular lattices.
//
// What "exact" means on a lattice. With uniform volumes V = dx^D, the difference gradient of
// a linear field f = a + b.x is
//   grad f_i = sum_j V (b.(x_j - x_i)) F_ij r_ij = M b,   M = -V sum_j F_ij r_ij (x) r_ij,
// and on a square/cubic lattice M = m I by symmetry, where m = 1 + e and e is the lattice
// quadrature error of the kernel's first moment (m -> 1 as h/dx grows). Likewise the
// Laplacian (thesis eq. 3.37) of x^2 is 2m, so lap(x^2 + 2 y^2) = 6 m. The tests therefore
// check two things separately:
//   (1) the operator reproduces the lattice value m b (or 6 m) to rounding (~1e-10
//       relative), with m summed independently here from Kernel::dWdr over lattice offsets:
//       this pins down the implementation (terms, signs, volumes, fixed neighbours, periodic
//       images);
//   (2) |m - 1| is within the tolerance that the kernel's lattice quadrature error allows,
//       which pins down the kernel scaling and the continuum limit.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/operators.hpp"
#include "vesph/core/particles.hpp"

using namespace vesph;

namespace {

constexpr double kReferenceDensity = 1000.0;

// A lattice block of n^D cells of width dx from the origin, particles at cell centres.
// With `frame` > 0 layers, the outer `frame` layers are fixed wall particles and the rest
// moving fluid (moving added first, as ParticleSet requires); the domain is then
// non-periodic. With frame == 0 all particles move and every axis is periodic.
template <int D>
struct Lattice {
  ParticleSet<D> particles;
  Domain<D> domain;
  NeighbourList<D> list;
  Kernel kernel;
};

template <int D>
Lattice<D> makeLattice(int n, double dx, int frame, KernelType type, double h_over_dx) {
  Lattice<D> L;
  L.kernel = Kernel(type, D, h_over_dx * dx);
  L.domain.lo = Vec<D>::Zero();
  L.domain.hi = Vec<D>::Constant(n * dx);
  for (int a = 0; a < D; ++a) L.domain.periodic[a] = frame == 0;
  const double m = kReferenceDensity * std::pow(dx, D);
  std::size_t total = 1;
  for (int a = 0; a < D; ++a) total *= static_cast<std::size_t>(n);
  for (int pass = 0; pass < 2; ++pass) {  // moving particles, then fixed ones
    for (std::size_t c = 0; c < total; ++c) {
      std::size_t rem = c;
      Vec<D> x;
      bool in_frame = false;
      for (int a = 0; a < D; ++a) {
        const int k = static_cast<int>(rem % n);
        rem /= n;
        x[a] = (k + 0.5) * dx;
        in_frame = in_frame || k < frame || k >= n - frame;
      }
      if (in_frame != (pass == 1)) continue;
      L.particles.add(x, Vec<D>::Zero(), kReferenceDensity, m, in_frame ? ParticleKind::wall : ParticleKind::fluid,
                      L.particles.size());
    }
  }
  L.list.configure(L.domain, L.kernel.supportRadius(), 0.1 * dx);
  L.list.update(L.particles);
  return L;
}

// m = -dx^D sum over lattice offsets d != 0 inside the support of F(|d|) d_x^2, the lattice
// first moment (see the top of the file), from Kernel::dWdr directly.
template <int D>
double latticeMoment(const Kernel& k, double dx) {
  const int n = static_cast<int>(std::ceil(k.supportRadius() / dx)) + 1;
  const int nz = D == 3 ? n : 0;
  double s = 0;
  for (int a = -n; a <= n; ++a)
    for (int b = -n; b <= n; ++b)
      for (int c = -nz; c <= nz; ++c) {
        const double r = dx * std::sqrt(double(a * a + b * b + c * c));
        if (r == 0 || r >= k.supportRadius()) continue;
        s += -k.dWdr(r) / r * (a * dx) * (a * dx);
      }
  return s * std::pow(dx, D);
}

template <int D>
std::vector<double> fieldOf(const ParticleSet<D>& p, auto&& fn) {
  std::vector<double> f(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) f[i] = fn(Vec<D>(p.x(i)));
  return f;
}

std::string label(KernelType t, double hdx) {
  return std::string(kernelName(t)) + " h/dx=" + std::to_string(hdx);
}

// Linear and quadratic fields on a non-periodic block whose outer layers (at least one
// support thick) are fixed: every moving particle has a full, symmetric neighbourhood made
// of moving and fixed particles.
template <int D>
void polynomialChecks(KernelType type, double hdx, int n, double tol_m) {
  CAPTURE(label(type, hdx));
  const double dx = 0.02;
  const int frame = static_cast<int>(std::ceil(Kernel(type, D, hdx * dx).supportRadius() / dx));
  const Lattice<D> L = makeLattice<D>(n, dx, frame, type, hdx);
  const ParticleSet<D>& p = L.particles;
  REQUIRE(p.n_moving > 0);
  REQUIRE(p.nFixed() > 0);
  const double m = latticeMoment<D>(L.kernel, dx);
  MESSAGE(D, "D ", label(type, hdx), ": lattice first moment m - 1 = ", m - 1);
  CHECK(std::abs(m - 1.0) < tol_m);

  // Linear field f = a + b.x: both gradient forms give m b.
  Vec<D> b;
  for (int a = 0; a < D; ++a) b[a] = 0.7 - 1.9 * a;
  const double a0 = 3.5;
  const std::vector<double> f = fieldOf<D>(p, [&](const Vec<D>& x) { return a0 + b.dot(x); });
  const std::vector<double> gd = gradientDifference(p, L.list, L.kernel, L.domain, f);
  const std::vector<double> gs = gradientSymmetric(p, L.list, L.kernel, L.domain, f);
  REQUIRE(gd.size() == p.n_moving * D);
  REQUIRE(gs.size() == p.n_moving * D);
  // (1) Difference form: rounding only. Each term is O(|b| r) * |F| r V and there are ~100
  // of them, of total size ~|b|; 1e-10 relative to |b| allows ~1e6 ulps of rounding.
  // (2) Symmetric form: the constant part a0 adds 2 a0 sum_j V grad_i W_ij, zero on a
  // symmetric lattice up to rounding of size ~ eps a0 sum|grad W| V ~ eps a0 / h; with
  // a0 = 3.5, h ~ 0.03 this is ~1e-13, far below 1e-10 |b|.
  double worst_d = 0, worst_s = 0, worst_c = 0;
  for (std::size_t i = 0; i < p.n_moving; ++i)
    for (int a = 0; a < D; ++a) {
      worst_d = std::max(worst_d, std::abs(gd[D * i + a] - m * b[a]) / b.norm());
      worst_s = std::max(worst_s, std::abs(gs[D * i + a] - m * b[a]) / b.norm());
      worst_c = std::max(worst_c, std::abs(gd[D * i + a] - b[a]) / b.norm());
    }
  MESSAGE("  gradient of a linear field: |grad - m b|/|b| difference ", worst_d, ", symmetric ",
          worst_s, "; |grad - b|/|b| ", worst_c);
  CHECK(worst_d < 1e-10);
  CHECK(worst_s < 1e-10);
  CHECK(worst_c < tol_m * 1.000001);

  // Quadratic field: lap(x^2 + 2 y^2 [+ 3 z^2]) = 6 (2D) or 12 (3D) in the continuum,
  // 6 m or 12 m on the lattice. (1) The operator's rounding: the cross terms
  // -4 x_i sum V F d cancel by symmetry to ~eps |x_i| / h relative, and x_i <= n dx ~ 1,
  // so 1e-10 relative is ample.
  const double exact = D == 2 ? 6.0 : 12.0;
  const std::vector<double> fq = fieldOf<D>(p, [&](const Vec<D>& x) {
    double s = 0;
    for (int a = 0; a < D; ++a) s += (a + 1) * x[a] * x[a];
    return s;
  });
  const std::vector<double> lap = laplacian(p, L.list, L.kernel, L.domain, fq);
  REQUIRE(lap.size() == p.n_moving);
  double worst_l = 0, worst_lc = 0;
  for (std::size_t i = 0; i < p.n_moving; ++i) {
    worst_l = std::max(worst_l, std::abs(lap[i] - exact * m) / exact);
    worst_lc = std::max(worst_lc, std::abs(lap[i] - exact) / exact);
  }
  MESSAGE("  Laplacian of a quadratic field: |lap - ", exact, " m|/", exact, " = ", worst_l,
          "; |lap - ", exact, "|/", exact, " = ", worst_lc);
  CHECK(worst_l < 1e-10);
  CHECK(worst_lc < tol_m * 1.000001);

  // The difference gradient ignores constants exactly (f_j - f_i); the Laplacian too.
  std::vector<double> f2 = f;
  for (double& v : f2) v += 1e3;
  const std::vector<double> gd2 = gradientDifference(p, L.list, L.kernel, L.domain, f2);
  double shift = 0;
  for (std::size_t k = 0; k < gd.size(); ++k) shift = std::max(shift, std::abs(gd2[k] - gd[k]));
  CHECK(shift < 1e-9 * b.norm());  // rounding of f (~1e3 * eps) over ~|F| r V ~ 1/h terms
}

}  // namespace

// Tolerances on |m - 1| (also the relative accuracy of the gradient of a linear field and of
// the Laplacian of a quadratic field). Measured on the lattice (m - 1): 2D quintic -5.3e-4
// (h = 1.6 dx), -6.7e-6 (2 dx); 2D cubic -6.7e-3 (1.6 dx), -9.0e-4 (2 dx); 2D Wendland C2
// -4.2e-3 (1.6 dx); 3D cubic -6.7e-4 (1.6 dx); 3D quintic -1.4e-4 (1.6 dx) with the correct
// normalisation 1/(120 pi h^3) (see test_kernels.cpp). The tolerances are about twice the
// measured values: m is a lattice property fixed by the kernel and h/dx, not noise, and a
// factor-2 error (Laplacian sign or factor), a wrong kernel constant or a missing neighbour
// class fails.
TEST_CASE("operators: linear and quadratic fields on a 2D lattice, quintic h = 1.6 dx") {
  polynomialChecks<2>(KernelType::quintic, 1.6, 40, 1.2e-3);
}

TEST_CASE("operators: linear and quadratic fields on a 2D lattice, quintic h = 2 dx") {
  polynomialChecks<2>(KernelType::quintic, 2.0, 40, 2e-5);
}

TEST_CASE("operators: linear and quadratic fields on a 2D lattice, cubic h = 1.6 dx") {
  polynomialChecks<2>(KernelType::cubic, 1.6, 30, 1.5e-2);
}

TEST_CASE("operators: linear and quadratic fields on a 2D lattice, cubic h = 2 dx") {
  polynomialChecks<2>(KernelType::cubic, 2.0, 30, 2e-3);
}

TEST_CASE("operators: linear and quadratic fields on a 2D lattice, Wendland C2 h = 1.6 dx") {
  polynomialChecks<2>(KernelType::wendland_c2, 1.6, 30, 1e-2);
}

TEST_CASE("operators: linear and quadratic fields on a 3D lattice, quintic h = 1.6 dx") {
  polynomialChecks<3>(KernelType::quintic, 1.6, 18, 3e-4);
}

TEST_CASE("operators: linear and quadratic fields on a 3D lattice, cubic h = 1.6 dx") {
  polynomialChecks<3>(KernelType::cubic, 1.6, 16, 1.5e-3);
}

namespace {

// A sine wave along x on a fully periodic lattice (all particles moving): every particle,
// including those next to the seam, needs the minimum image. On the lattice
//   grad_x f_i = G cos(k x_i),  G = -V sum_d F(|d|) d_x sin(k d_x)            (-> k)
//   lap f_i    = Lam sin(k x_i), Lam = 2 V sum_d F(|d|) (1 - cos(k d_x))      (-> -k^2)
// (the other parts cancel by the lattice symmetry d -> -d), with G and Lam summed here over
// lattice offsets.
template <int D>
void sineChecks(KernelType type, double hdx, int n, double tol_g, double tol_l) {
  CAPTURE(label(type, hdx));
  const double dx = 0.01;
  const Lattice<D> L = makeLattice<D>(n, dx, 0, type, hdx);
  const ParticleSet<D>& p = L.particles;
  REQUIRE(p.n_moving == p.size());
  const double k = 2 * M_PI / (n * dx), V = std::pow(dx, D);
  double G = 0, Lam = 0;
  {
    const int nn = static_cast<int>(std::ceil(L.kernel.supportRadius() / dx)) + 1;
    const int nz = D == 3 ? nn : 0;
    for (int a = -nn; a <= nn; ++a)
      for (int b = -nn; b <= nn; ++b)
        for (int c = -nz; c <= nz; ++c) {
          const double r = dx * std::sqrt(double(a * a + b * b + c * c));
          if (r == 0 || r >= L.kernel.supportRadius()) continue;
          const double F = L.kernel.dWdr(r) / r, d = a * dx;
          G += -V * F * d * std::sin(k * d);
          Lam += 2 * V * F * (1 - std::cos(k * d));
        }
  }
  MESSAGE(D, "D ", label(type, hdx), " sine, kh = ", k * L.kernel.h, ": G/k - 1 = ", G / k - 1,
          ", Lam/(-k^2) - 1 = ", -Lam / (k * k) - 1);
  CHECK(std::abs(G / k - 1) < tol_g);
  CHECK(std::abs(-Lam / (k * k) - 1) < tol_l);

  const std::vector<double> f = fieldOf<D>(p, [&](const Vec<D>& x) { return std::sin(k * x[0]); });
  const std::vector<double> gd = gradientDifference(p, L.list, L.kernel, L.domain, f);
  const std::vector<double> gs = gradientSymmetric(p, L.list, L.kernel, L.domain, f);
  const std::vector<double> lap = laplacian(p, L.list, L.kernel, L.domain, f);
  // Rounding only: terms of size ~k dx |F| r V, a few hundred of them; 1e-10 of k (or k^2).
  double wd = 0, ws = 0, wl = 0;
  for (std::size_t i = 0; i < p.n_moving; ++i) {
    const double xi = p.position[D * i];
    for (int a = 0; a < D; ++a) {
      const double expect = a == 0 ? G * std::cos(k * xi) : 0.0;
      wd = std::max(wd, std::abs(gd[D * i + a] - expect) / k);
      ws = std::max(ws, std::abs(gs[D * i + a] - expect) / k);
    }
    wl = std::max(wl, std::abs(lap[i] - Lam * std::sin(k * xi)) / (k * k));
  }
  CHECK(wd < 1e-10);
  CHECK(ws < 1e-10);
  CHECK(wl < 1e-10);
}

}  // namespace

// Continuum accuracy of the sine wave: G/k - 1 and -Lam/k^2 - 1 combine the lattice error
// m - 1 with the smoothing error O((kh)^2) (both operators see the field averaged over the
// kernel, which damps the wave). Measured: 2D quintic, kh = 0.157: G/k - 1 = -6.5e-3,
// -Lam/k^2 - 1 = -3.5e-3; 3D Wendland C2, kh = 0.503: -3.4e-2 and -1.7e-2. Tolerances about
// twice those; the exactness checks inside sineChecks carry the implementation test.
TEST_CASE("operators: sine wave on a periodic 2D lattice, quintic h = 1.6 dx") {
  sineChecks<2>(KernelType::quintic, 1.6, 64, 1.3e-2, 7e-3);
}

TEST_CASE("operators: sine wave on a periodic 3D lattice, Wendland C2 h = 1.6 dx") {
  sineChecks<3>(KernelType::wendland_c2, 1.6, 20, 7e-2, 3.5e-2);
}

// Exact identities on an irregular, fully periodic particle set with varying masses and
// densities: the symmetric gradient (eq. 3.18) and the Laplacian (eq. 3.37) are built from
// pair terms antisymmetric in i and j, so sum_i V_i grad f_i = 0 and sum_i V_i lap f_i = 0
// (momentum and, for the Laplacian, heat conservation); the difference gradient (eq. 3.17)
// ignores an added constant exactly. Rounding only: compared with sum_i V_i |grad f_i|, at
// 1e-12.
TEST_CASE("operators: conservation identities on a disordered periodic set") {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dx = 0.02, jitter = 0.3 * dx;
  Lattice<2> L = makeLattice<2>(32, dx, 0, KernelType::quintic, 1.5);
  ParticleSet<2>& p = L.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    for (int a = 0; a < 2; ++a) p.position[2 * i + a] = L.domain.wrap(a, p.position[2 * i + a] + jitter * u(rng));
    p.density[i] = kReferenceDensity * (1 + 0.05 * u(rng));
    p.mass[i] *= 1 + 0.1 * u(rng);
  }
  L.list.update(p, true);
  const double k = 2 * M_PI / L.domain.length(0);
  std::vector<double> f(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) f[i] = std::cos(k * p.position[2 * i]) + 0.3 * u(rng);
  const std::vector<double> gs = gradientSymmetric(p, L.list, L.kernel, L.domain, f);
  const std::vector<double> lap = laplacian(p, L.list, L.kernel, L.domain, f);
  const std::vector<double> gd = gradientDifference(p, L.list, L.kernel, L.domain, f);
  double sg[2] = {0, 0}, sg_abs = 0, sl = 0, sl_abs = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double V = p.mass[i] / p.density[i];
    for (int a = 0; a < 2; ++a) {
      sg[a] += V * gs[2 * i + a];
      sg_abs += V * std::abs(gs[2 * i + a]);
    }
    sl += V * lap[i];
    sl_abs += V * std::abs(lap[i]);
  }
  CHECK(sg_abs > 0);
  CHECK(std::abs(sg[0]) < 1e-12 * sg_abs);
  CHECK(std::abs(sg[1]) < 1e-12 * sg_abs);
  CHECK(std::abs(sl) < 1e-12 * sl_abs);

  std::vector<double> f2 = f;
  for (double& v : f2) v -= 7.0;
  const std::vector<double> gd2 = gradientDifference(p, L.list, L.kernel, L.domain, f2);
  const std::vector<double> gs2 = gradientSymmetric(p, L.list, L.kernel, L.domain, f2);
  double dd = 0, ds = 0, scale = 0;
  for (std::size_t k2 = 0; k2 < gd.size(); ++k2) {
    dd = std::max(dd, std::abs(gd2[k2] - gd[k2]));
    ds = std::max(ds, std::abs(gs2[k2] - gs[k2]));
    scale = std::max(scale, std::abs(gd[k2]));
  }
  CHECK(dd < 1e-10 * scale);
  // The symmetric form is not blind to constants on a disordered set: 2 c sum_j m_j/rho_i
  // grad_i W_ij no longer cancels. Checked so that this test notices if the two forms are
  // ever swapped.
  CHECK(ds > 1e-3 * scale);
}

TEST_CASE("operators: inputs of the wrong size are rejected") {
  const Lattice<2> L = makeLattice<2>(16, 0.01, 0, KernelType::cubic, 1.3);
  std::vector<double> f(L.particles.n_moving - 1, 0.0);
  CHECK_THROWS_AS(gradientDifference(L.particles, L.list, L.kernel, L.domain, f), std::invalid_argument);
  CHECK_THROWS_AS(gradientSymmetric(L.particles, L.list, L.kernel, L.domain, f), std::invalid_argument);
  CHECK_THROWS_AS(laplacian(L.particles, L.list, L.kernel, L.domain, f), std::invalid_argument);
  f.resize(L.particles.size());
  CHECK_NOTHROW(laplacian(L.particles, L.list, L.kernel, L.domain, f));
}
