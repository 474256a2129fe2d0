#include "vesph/core/operators.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace vesph {
namespace {

template <int D>
void checkInputs(const char* op, const ParticleSet<D>& p, const NeighbourList<D>& list,
                 const Kernel& kernel, const std::vector<double>& f) {
  const std::string where = std::string("vesph::") + op + ": ";
  if (kernel.dim != D) throw std::invalid_argument(where + "kernel dimension differs from D");
  if (f.size() != p.size())
    throw std::invalid_argument(where + "the field needs one value per particle (all particles)");
  if (list.start.size() != p.size() + 1 || list.split.size() != p.size())
    throw std::invalid_argument(where + "the neighbour list was not built for this particle set");
}

// Calls fn(j, rij, F) for every neighbour j of moving particle i (moving ones, then fixed)
// inside the kernel support, with rij = xi - xj (minimum image) and F = (dW/dr)/r. Same pair
// selection as PairDriver::gather: r >= support and r == 0 are skipped.
template <int D, class Shape, class Fn>
void forNeighbours(Shape, const ParticleSet<D>& p, const NeighbourList<D>& list,
                   const Kernel& kernel, const Domain<D>& domain, std::size_t i, Fn&& fn) {
  const double inv_h = 1.0 / kernel.h;
  const double cut2 = kernel.supportRadius() * kernel.supportRadius();
  const double fs = kernel.dw_scale * inv_h;  // F = (sigma/h^(D+1)) f'(q) / (q h)
  for (std::size_t k = list.start[i]; k < list.start[i + 1]; ++k) {
    const Index j = list.nbr[k];
    Vec<D> rij;
    for (int a = 0; a < D; ++a) rij[a] = domain.image(a, p.position[D * i + a] - p.position[D * j + a]);
    const double r2 = rij.squaredNorm();
    if (r2 >= cut2 || r2 == 0.0) continue;
    const double q = std::sqrt(r2) * inv_h;
    fn(j, rij, fs * Shape::df_over_q(q));
  }
}

}  // namespace

template <int D>
std::vector<double> gradientDifference(const ParticleSet<D>& p, const NeighbourList<D>& list,
                                       const Kernel& kernel, const Domain<D>& domain,
                                       const std::vector<double>& f) {
  checkInputs("gradientDifference", p, list, kernel, f);
  const std::size_t n = p.n_moving;
  std::vector<double> out(n * D, 0.0);
  kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      // thesis eq. (3.17): grad f_i = sum_j (m_j/rho_j) (f_j - f_i) grad_i W_ij
      Vec<D> g = Vec<D>::Zero();
      const double fi = f[i];
      forNeighbours<D>(shape, p, list, kernel, domain, i, [&](Index j, const Vec<D>& rij, double F) {
        g += (p.mass[j] / p.density[j] * (f[j] - fi) * F) * rij;
      });
      for (int a = 0; a < D; ++a) out[D * i + a] = g[a];
    }
  });
  return out;
}

template <int D>
std::vector<double> gradientSymmetric(const ParticleSet<D>& p, const NeighbourList<D>& list,
                                      const Kernel& kernel, const Domain<D>& domain,
                                      const std::vector<double>& f) {
  checkInputs("gradientSymmetric", p, list, kernel, f);
  const std::size_t n = p.n_moving;
  std::vector<double> out(n * D, 0.0);
  kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      // thesis eq. (3.18): grad f_i = rho_i sum_j m_j (f_i/rho_i^2 + f_j/rho_j^2) grad_i W_ij
      Vec<D> g = Vec<D>::Zero();
      const double rhoi = p.density[i], fi_over_rho2 = f[i] / (rhoi * rhoi);
      forNeighbours<D>(shape, p, list, kernel, domain, i, [&](Index j, const Vec<D>& rij, double F) {
        const double rhoj = p.density[j];
        g += (p.mass[j] * (fi_over_rho2 + f[j] / (rhoj * rhoj)) * F) * rij;
      });
      for (int a = 0; a < D; ++a) out[D * i + a] = rhoi * g[a];
    }
  });
  return out;
}

template <int D>
std::vector<double> laplacian(const ParticleSet<D>& p, const NeighbourList<D>& list,
                              const Kernel& kernel, const Domain<D>& domain,
                              const std::vector<double>& f) {
  checkInputs("laplacian", p, list, kernel, f);
  const std::size_t n = p.n_moving;
  std::vector<double> out(n, 0.0);
  kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      // thesis eq. (3.37): lap f_i = 2 sum_j (m_j/rho_j) (f_i - f_j) (1/r_ij) dW/dr
      // (sign derived in operators.hpp: +2 for f = x^2, since dW/dr <= 0)
      double s = 0.0;
      const double fi = f[i];
      forNeighbours<D>(shape, p, list, kernel, domain, i, [&](Index j, const Vec<D>&, double F) {
        s += p.mass[j] / p.density[j] * (fi - f[j]) * F;
      });
      out[i] = 2.0 * s;
    }
  });
  return out;
}

#define VESPH_INSTANTIATE_OPERATORS(D)                                                            \
  template std::vector<double> gradientDifference<D>(const ParticleSet<D>&, const NeighbourList<D>&, \
                                                     const Kernel&, const Domain<D>&,            \
                                                     const std::vector<double>&);                \
  template std::vector<double> gradientSymmetric<D>(const ParticleSet<D>&, const NeighbourList<D>&, \
                                                    const Kernel&, const Domain<D>&,             \
                                                    const std::vector<double>&);                 \
  template std::vector<double> laplacian<D>(const ParticleSet<D>&, const NeighbourList<D>&,       \
                                            const Kernel&, const Domain<D>&,                     \
                                            const std::vector<double>&);
VESPH_INSTANTIATE_OPERATORS(2)
VESPH_INSTANTIATE_OPERATORS(3)
#undef VESPH_INSTANTIATE_OPERATORS

}  // namespace vesph
