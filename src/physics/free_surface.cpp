// Free-surface detection. Two methods (effects.free_surface.method):
//
// "number_density" (the default), thesis §4.2:
//   n_i = sum_j W(r_ij, h)   (the particle itself included, W(0))
//   particle i is on the free surface when n_i <= threshold * n_ref   (threshold 0.8)
// The kernel support of a particle at or near the surface is truncated, so its number density
// drops. The thesis takes n_ref = max_i n_i; here n_ref is the number density of a particle
// with a full support on the initial lattice (computed once at setup), which is what max_i n_i
// is in any flow with one interior particle, without a global reduction inside the right-hand
// side (and so the flag of a particle does not depend on particles far away). A scalar test:
// once the particles are disordered, n_i of interior particles scatters by several per cent
// (cubic spline, h = 1.5 dx: 0.95-1.05), so a threshold close to 1 flags interior particles too.
//
// "marrone", Marrone et al. (2010, J. Comput. Phys. 229, 3652, §2.1-2.2): a geometric test
// that looks for empty space beside the particle.
//   M_i = -sum_j V_j F_ij r_ij r_ij^T       (the renormalisation matrix; the identity on a full
//                                            support, vesph/core/renormalisation.hpp)
//   lambda_i = smallest eigenvalue of M_i
//   lambda_i <= lambda_surface (0.2):        on the free surface (a thin filament, a lone particle)
//   lambda_i >  lambda_interior (0.75):      inside
//   otherwise the scan region decides: the normal nu_i = -M_i^-1 sum_j V_j grad_i W_ij
//   (normalised; it points out of the fluid), T = x_i + hs nu_i with hs = half the support
//   radius (Marrone's h, kernel support 2h); a neighbour j blocks the particle when
//     |x_ji| <  sqrt(2) hs and the angle between x_ji and nu_i is below pi/4, or
//     |x_ji| >= sqrt(2) hs and |x_j - T| < hs;
//   the particle is on the free surface when no neighbour blocks it.
// The scan region is empty only outside the fluid, so a particle beside a small gap inside a
// disordered bulk keeps its flag off; only the outermost row is flagged (on a lattice with a
// flat surface, cubic spline h = 1.5 dx: lambda = 0.50, 0.82, 1.0 on rows 0, 1, 2).
// Wall particles count as neighbours, in M_i, in the normal and in the scan region (a fluid
// particle on a wall is not on the free surface); V_j = m_j / rho_j.
// With a threshold as well (method = "marrone", threshold = theta), a second sweep over the
// particles also flags every particle with n_i <= theta n_ref that has an outermost particle
// within its support: the rows whose support the surface cuts (which the ISPH projection needs
// as Dirichlet rows, docs/theory.md §10), without the interior particles whose number density
// the disorder lowers. Without a threshold the method runs no second sweep.
//
// Writes "number_density" (moving particles) and "free_surface" (1 on the surface, 0 inside;
// all particles, walls 0), which the output stores. When the scene has
// [effects.surface_pressure] (or the ISPH projection's solver.surface_pressure =
// "normal_stress"), also "surface_normal" (moving particles, D components): the unit
// outward normal n_i = -g_i/|g_i| with g_i = sum_j V_j grad_i W_ij over fluid and wall
// neighbours (V_j = m_j/rho_j), the direction in which the support is empty; zero where
// |g_i| < 1e-6/h (a full, symmetric support). Used by the pressure gradient's mirrored
// zero-pressure treatment (thesis eq. 4.1, effects.pressure_gradient.free_surface_mirror) and by
// the ISPH projection (p = 0 on the flagged particles, src/isph/projection.cpp).
#include <cmath>

#include <Eigen/Eigenvalues>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class FreeSurface final : public Effect<D> {
 public:
  explicit FreeSurface(ConfigTable& cfg) {
    marrone_ = cfg.choice("method", "number_density", {"number_density", "marrone"}) == "marrone";
    if (marrone_) {
      lambda_surface_ = cfg.numberIn("lambda_surface", 0.2, 0.0, 1.0, "smallest eigenvalue of the renormalisation matrix");
      lambda_interior_ = cfg.numberIn("lambda_interior", 0.75, 0.0, 1.0, "smallest eigenvalue of the renormalisation matrix");
      if (lambda_interior_ < lambda_surface_)
        cfg.fail("lambda_interior", "at least lambda_surface (" + std::to_string(lambda_surface_) + ")");
      near_surface_ = cfg.has("threshold");
    } else {
      for (const char* key : {"lambda_surface", "lambda_interior"})
        if (cfg.has(key)) cfg.fail(key, "absent with method = \"number_density\" (set method = \"marrone\")");
    }
    threshold_ = cfg.numberIn("threshold", 0.8, 0.05, 0.99, "of the full-support number density");
  }
  std::string_view name() const override { return "free_surface"; }
  Phase phase() const override { return Phase::gradients; }
  bool pairwise() const override { return true; }
  bool needsKernelValue() const override { return true; }

  void setup(Setup<D>& s) override {
    density_ = &s.particles.fields.require("number_density", 1, Field::Range::moving);
    flag_ = &s.particles.fields.require("free_surface", 1, Field::Range::all);
    if (near_surface_) outermost_ = &s.particles.fields.require("free_surface_outermost", 1, Field::Range::moving);
    // The outward normals for [effects.surface_pressure], or for whoever requested the field
    // before this setup (the ISPH projection's solver.surface_pressure = "normal_stress").
    if (s.find("surface_pressure") || s.particles.fields.find("surface_normal")) {
      normal_ = &s.particles.fields.require("surface_normal", D, Field::Range::moving);
      normal_floor_ = 1e-6 / s.kernel.h;
    }
    // n_ref: the lattice sum of W over a full support, spacing dx, the particle itself included.
    const double n = s.kernel.latticeSum(s.spacing);
    limit_ = threshold_ * n;
    self_ = s.kernel.visit([&](auto shape) { return s.kernel.w_scale * decltype(shape)::f(0.0); });
    scan_ = 0.5 * s.kernel.supportRadius();
  }

  void interact(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                std::span<const Neighbour<D>> fixed) const override {
    double n = self_;
    for (const Neighbour<D>& nb : moving) n += nb.W;
    for (const Neighbour<D>& nb : fixed) n += nb.W;
    density_->data[i] = n;
    const double flag = (marrone_ ? marroneSurface(ctx, moving, fixed) : n <= limit_) ? 1.0 : 0.0;
    flag_->data[i] = flag;
    // The second sweep decides only the particles that are not outermost and not too dense.
    if (near_surface_) outermost_->data[i] = flag;
    if (normal_) storeNormal(ctx, i, moving, fixed);
  }

  // With method = "marrone" and a threshold: a particle whose number density is at most
  // threshold n_ref is flagged too when an outermost particle (the first sweep's Marrone
  // flag) lies within its support.
  // Particles that are outermost, or too dense to be flagged, keep the first sweep's flag;
  // the second sweep gathers the neighbours of the rest only.
  bool secondSweep() const override { return near_surface_; }
  bool sweepAgain(const RhsContext<D>&, Index i) const override {
    return outermost_->data[i] < 0.5 && density_->data[i] <= limit_;
  }
  void interactAgain(const RhsContext<D>&, Index i, std::span<const Neighbour<D>> moving,
                     std::span<const Neighbour<D>>) const override {
    const double* outer = outermost_->data.data();
    bool flag = false;
    for (std::size_t k = 0; k < moving.size() && !flag; ++k) flag = outer[moving[k].j] > 0.5;
    flag_->data[i] = flag ? 1.0 : 0.0;
  }

 private:
  using Mat = Eigen::Matrix<double, D, D>;

  // n_i = -g_i/|g_i|, g_i = sum_j V_j grad_i W_ij: grad_i W_ij = F_ij r_ij points from the
  // neighbour towards i scaled by F < 0, so g_i points into the fluid.
  void storeNormal(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                   std::span<const Neighbour<D>> fixed) const {
    const ParticleSet<D>& p = ctx.particles;
    Vec<D> g = Vec<D>::Zero();
    for (const Neighbour<D>& nb : moving) g += (p.mass[nb.j] / p.density[nb.j] * nb.F) * nb.rij;
    for (const Neighbour<D>& nb : fixed) g += (p.mass[nb.j] / p.density[nb.j] * nb.F) * nb.rij;
    const double length = g.norm();
    const Vec<D> n = length > normal_floor_ ? Vec<D>(-g / length) : Vec<D>::Zero();
    for (int a = 0; a < D; ++a) normal_->data[D * i + a] = n[a];
  }

  bool marroneSurface(const RhsContext<D>& ctx, std::span<const Neighbour<D>> moving,
                      std::span<const Neighbour<D>> fixed) const {
    const ParticleSet<D>& p = ctx.particles;
    Mat M = Mat::Zero();
    Vec<D> g = Vec<D>::Zero();
    auto moments = [&](std::span<const Neighbour<D>> nbs) {
      for (const Neighbour<D>& nb : nbs) {
        const double V = p.mass[nb.j] / p.density[nb.j];
        M.noalias() -= (V * nb.F) * nb.rij * nb.rij.transpose();
        g += (V * nb.F) * nb.rij;
      }
    };
    moments(moving);
    moments(fixed);
    const double lambda = Eigen::SelfAdjointEigenSolver<Mat>(M, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
    if (lambda <= lambda_surface_) return true;
    if (lambda > lambda_interior_) return false;
    // lambda > lambda_surface > 0 (or lambda_surface = 0 and lambda > 0): M is invertible.
    Vec<D> normal = -(M.inverse() * g);
    const double length = normal.norm();
    if (!(length > 0)) return false;  // no preferred direction: a symmetric neighbourhood
    normal /= length;
    const double cone_reach = std::sqrt(2.0) * scan_, cos_cone = std::sqrt(0.5);
    auto blocks = [&](const Neighbour<D>& nb) {
      const Vec<D> xji = -nb.rij;  // x_j - x_i
      if (nb.r < cone_reach) return xji.dot(normal) > cos_cone * nb.r;
      return (xji - scan_ * normal).squaredNorm() < scan_ * scan_;
    };
    for (const Neighbour<D>& nb : moving)
      if (blocks(nb)) return false;
    for (const Neighbour<D>& nb : fixed)
      if (blocks(nb)) return false;
    return true;
  }

  bool marrone_ = false;
  double threshold_ = 0.8, limit_ = 0, self_ = 0;
  double lambda_surface_ = 0.2, lambda_interior_ = 0.75, scan_ = 0;
  bool near_surface_ = false;
  Field* density_ = nullptr;
  Field* flag_ = nullptr;
  Field* outermost_ = nullptr;
  Field* normal_ = nullptr;  // only with [effects.surface_pressure] or ISPH's normal-stress surface
  double normal_floor_ = 0;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeFreeSurface, FreeSurface)
}  // namespace vesph
