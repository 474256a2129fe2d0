#pragma once
// Reference SPH operators of a per-particle scalar field, for tests and diagnostics (not for
// the right-hand side: effects go through the pair driver). They run on the neighbour loop of
// vesph/core/pair_loop.hpp, as the pair driver does.
//
// Every function evaluates its operator at each moving particle i in [0, n_moving) from all
// its neighbours j in a built NeighbourList (moving and fixed ones alike), with the same
// pair selection as the pair driver: pairs with r >= kernel support or r == 0 are skipped.
// f holds one value per particle and covers ALL particles (moving, then fixed).
//
// Conventions (as in vesph/core/pair_loop.hpp, Neighbour):
//   r_ij = x_i - x_j           minimum image along periodic axes,  r = |r_ij|
//   F_ij = (dW/dr)(r) / r      negative inside the support for all kernels of kernel.hpp
//   grad_i W_ij = F_ij r_ij    the kernel gradient with respect to x_i
//   V_j = m_j / rho_j          the neighbour's volume
//
//   gradientDifference  thesis eq. (3.17):  grad f_i = sum_j V_j (f_j - f_i) grad_i W_ij
//   gradientSymmetric   thesis eq. (3.18):  grad f_i = rho_i sum_j m_j (f_i/rho_i^2 + f_j/rho_j^2)
//                                                                    grad_i W_ij
//   laplacian           thesis eq. (3.37):  lap f_i  = 2 sum_j V_j (f_i - f_j) F_ij
//
// Sign of the Laplacian. Take f = x^2 and x_i = 0: f_i - f_j = -(x_j)^2 = -r^2 cos^2(theta),
// so each term is -2 V_j r cos^2(theta) dW/dr >= 0 (dW/dr <= 0). In the continuum limit (2D)
//   2 int (-r cos^2 theta) W'(r) dA = 2 pi int_0^inf -r^2 W'(r) dr = 2 pi int_0^inf 2 r W dr = 2,
// using integration by parts and int W dA = 2 pi int r W dr = 1 (3D likewise, with
// <cos^2> = 1/3 and int W dV = 4 pi int r^2 W dr = 1). So (f_i - f_j) with F = (dW/dr)/r, as
// printed in eq. (3.37), is the right sign: lap(x^2) = +2. With the opposite difference
// (f_j - f_i) the sign flips.
//
// Accuracy. On a regular lattice these sums are quadratures of the continuum integrals, so
// even a linear field's gradient carries the lattice quadrature error of the kernel's first
// moment, -sum_j V_j F_ij r_ij (x) r_ij = (1 + e) I, where e depends on the kernel and h/dx
// (at h = 1.6 dx: -5e-4 quintic, -4e-3 Wendland C2, -7e-3 cubic in 2D; tests/test_operators.cpp
// measures it). The Laplacian of a quadratic carries the same factor. The difference
// form has no error from the constant part of f (it cancels exactly), the symmetric form
// does where sum_j m_j grad_i W_ij != 0 (disordered particles, near free surfaces).
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

// Gradient by thesis eq. (3.17); returns n_moving * D values (particle-major).
template <int D>
std::vector<double> gradientDifference(const ParticleSet<D>& particles, const NeighbourList<D>& list,
                                       const Kernel& kernel, const Domain<D>& domain,
                                       const std::vector<double>& f);

// Gradient by thesis eq. (3.18) (multiplied through by rho_i); returns n_moving * D values.
template <int D>
std::vector<double> gradientSymmetric(const ParticleSet<D>& particles, const NeighbourList<D>& list,
                                      const Kernel& kernel, const Domain<D>& domain,
                                      const std::vector<double>& f);

// Laplacian by thesis eq. (3.37) (Brookshaw's form); returns n_moving values.
template <int D>
std::vector<double> laplacian(const ParticleSet<D>& particles, const NeighbourList<D>& list,
                              const Kernel& kernel, const Domain<D>& domain,
                              const std::vector<double>& f);

}  // namespace vesph
