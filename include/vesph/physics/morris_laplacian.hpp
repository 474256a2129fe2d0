// Morris, Fox & Zhu (1997) eq. (8), the SPH Laplacian of the velocity with viscosity mu, shared
// by the viscous force (src/physics/viscosity.cpp) and the elastic-viscous split of the stress
// divergence (src/physics/stress_divergence.cpp):
//   dv_i/dt += sum_j w_ij (v_i - v_j),   w_ij = m_j (2 mu / rho_i) / rho_j F_ij   (F_ij < 0)
#pragma once

#include <span>

#include "vesph/physics/effect.hpp"

namespace vesph::morris {

// w_ij from m_j, 2 mu / rho_i, rho_j and F_ij (the factors in this order: the pair loops' sums
// depend on it to the last bit).
inline double weight(double m_j, double two_mu_over_rhoi, double rho_j, double F) {
  return m_j * two_mu_over_rhoi / rho_j * F;
}

// Particle i's row of the Laplacian's velocity coupling (Effect::velocityCoupling):
// d(dv_i/dt)/dv_j = -w_ij for a fluid neighbour j, and the diagonal sum_j w_ij. A wall
// neighbour b's velocity follows the fluid's by wall_dependence[b - n_moving] when the walls
// present an extrapolated no-slip velocity (walls_follow_fluid); its term is lumped onto the
// diagonal, w_ib (1 - that dependence), which keeps the row sums exact and the signs of an
// M-matrix (viscosity.cpp says why BoomerAMG needs them).
template <int D>
void addCouplingRow(const ParticleSet<D>& p, Index i, double mu, std::span<const Neighbour<D>> moving,
                    std::span<const Neighbour<D>> fixed, std::span<const double> wall_dependence,
                    bool walls_follow_fluid, VelocityCouplingRow& row) {
  const double two_mu_over_rhoi = 2.0 * mu / p.density[i];
  double diagonal = 0;
  for (const Neighbour<D>& nb : moving) {
    const double w = weight(p.mass[nb.j], two_mu_over_rhoi, p.density[nb.j], nb.F);
    diagonal += w;
    row.entries.emplace_back(nb.j, -w);
  }
  const std::size_t fixed0 = p.n_moving;
  for (const Neighbour<D>& nb : fixed)
    diagonal += weight(p.mass[nb.j], two_mu_over_rhoi, p.density[nb.j], nb.F) *
                (walls_follow_fluid ? 1.0 - wall_dependence[nb.j - fixed0] : 1.0);
  row.diagonal += diagonal;
}

}  // namespace vesph::morris
