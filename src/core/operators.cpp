#include "vesph/core/operators.hpp"

#include "vesph/core/pair_loop.hpp"

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

// Calls fn(i, j, rij, F) for every neighbour j of every moving particle i (moving ones, then
// fixed) inside the kernel support, through the one neighbour loop of vesph (core/pair_loop.hpp).
template <int D, class Fn>
void forPairs(const ParticleSet<D>& p, const NeighbourList<D>& list, const Kernel& kernel,
              const Domain<D>& domain, Fn&& fn) {
  PairLoop<D> loop;
  loop.forEachMoving(p, kernel, domain, list, false,
                     [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                       for (const Neighbour<D>& nb : moving) fn(i, nb.j, nb.rij, nb.F);
                       for (const Neighbour<D>& nb : fixed) fn(i, nb.j, nb.rij, nb.F);
                     });
}

}  // namespace

template <int D>
std::vector<double> gradientDifference(const ParticleSet<D>& p, const NeighbourList<D>& list,
                                       const Kernel& kernel, const Domain<D>& domain,
                                       const std::vector<double>& f) {
  checkInputs("gradientDifference", p, list, kernel, f);
  const std::size_t n = p.n_moving;
  std::vector<double> out(n * D, 0.0);
  // thesis eq. (3.17): grad f_i = sum_j (m_j/rho_j) (f_j - f_i) grad_i W_ij
  forPairs(p, list, kernel, domain, [&](Index i, Index j, const Vec<D>& rij, double F) {
    const double c = p.mass[j] / p.density[j] * (f[j] - f[i]) * F;
    for (int a = 0; a < D; ++a) out[D * i + a] += c * rij[a];
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
  // thesis eq. (3.18): grad f_i = rho_i sum_j m_j (f_i/rho_i^2 + f_j/rho_j^2) grad_i W_ij
  forPairs(p, list, kernel, domain, [&](Index i, Index j, const Vec<D>& rij, double F) {
    const double rhoi = p.density[i], rhoj = p.density[j];
    const double c = rhoi * p.mass[j] * (f[i] / (rhoi * rhoi) + f[j] / (rhoj * rhoj)) * F;
    for (int a = 0; a < D; ++a) out[D * i + a] += c * rij[a];
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
  // thesis eq. (3.37): lap f_i = 2 sum_j (m_j/rho_j) (f_i - f_j) (1/r_ij) dW/dr
  // (sign derived in operators.hpp: +2 for f = x^2, since dW/dr <= 0)
  forPairs(p, list, kernel, domain, [&](Index i, Index j, const Vec<D>&, double F) {
    out[i] += 2.0 * p.mass[j] / p.density[j] * (f[i] - f[j]) * F;
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
