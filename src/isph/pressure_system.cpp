// The pressure equation of the ISPH projection (docs/theory.md §10; docs/architecture.md
// "ISPH projection"): the unknowns, the continuity divergence, the gradient rows and the
// assembly.
//
// The pressure Poisson equation of thesis §3.5,
//     div(grad p / rho) = div(v*) / dt,
// with the divergence of the continuity equation (Fang eq. 26),
//     div(v)_i = -(1/rho_i) sum_j m_j (v_i - v_j) . grad_i W_ij,
// and one of two Laplacians (solver.laplacian), both one kernel support wide:
//   morris      thesis eq. (3.37) in the variable-density form of Cummins & Rudman (1999),
//                   L p_i = sum_j k_ij (p_i - p_j),
//                   k_ij = -8 rho_i m_j F_ij / (rho_i + rho_j)^2,  F_ij = (dW/dr)/r,
//               (L p ~ -lap p); it is exact for linear fields only where the kernel support
//               is full: a truncated support (the particle rows within a support of the
//               free surface) turns a linear pressure into a spurious source;
//   consistent  (default) the same with the first-order error removed (Schwaiger 2008;
//               Fatehi & Manzari 2011):
//                   L p_i = sum_j k_ij (p_i - p_j - r_ij . grad p_i),
//               grad p_i the renormalised gradient below: exact for linear fields on any
//               support, so a hydrostatic pressure is reproduced up to the free surface.
// The equation solved is L p_i = -rho_i div(v*)_i / dt. The projection is approximate
// (Cummins & Rudman): L is not the composition of the discrete divergence and gradient, so
// the divergence of the corrected velocity is reduced to the operators' truncation error,
// not to the solver tolerance. (The exact composition div_h G reaches two supports and
// annihilates pressure modes at the lattice scale: as the pressure equation it is
// near-singular, and its solutions grew without bound in the hydrostatic tank; it serves
// the divergence cleaning instead, src/isph/divergence_cleaning.cpp; docs/theory.md.)
// The walls' pressures are eliminated into the fluid rows (src/isph/wall_conditions.cpp).
//
// The gradient G of the correction (solver.gradient) is the renormalised difference form
// (default; Randles & Libersky 1996, exact for linear pressure fields, also at the free
// surface and the walls),
//     (G p)_i = (1/rho_i) M_i^-1 sum_j V_j (p_j - p_i) grad_i W_ij,
//     M_i = -sum_j V_j F_ij r_ij r_ij^T,  V_j = m_j/rho_j
// (M_i = I where it is near-singular: smallest eigenvalue below 0.1, an isolated particle),
// or thesis eq. (3.17) (difference, M = I) or (3.18) (symmetric, momentum-conserving).
//
// The matrix is assembled from the pairs inside the kernel support; when its pattern equals
// the previous step's (no pair crossed the support, the free surface kept its particles), the
// direct solvers keep their symbolic analysis.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "projection_parts.hpp"
#include "vesph/core/pair_loop.hpp"
#include "vesph/core/renormalisation.hpp"

namespace vesph::isph {
namespace {
// Relative diagonal shift of the exact projection's matrix (assemble()).
constexpr double kExactShift = 1e-10;
}  // namespace

template <int D>
void PressureUnknowns::number(const ParticleSet<D>& P, const double* surface_flag, ParticleDistribution<D>* dist) {
  const std::size_t n = P.n_moving, owned = P.ownedMoving();
  unknown_of.assign(n, -1);
  particle_of.clear();
  auto onSurface = [&](std::size_t i) { return surface_flag && surface_flag[i] > 0.5; };
  std::uint64_t surface = 0;
  for (std::size_t i = 0; i < owned; ++i)
    if (onSurface(i)) ++surface;
  if (dist) surface = dist->sum(surface);
  // No Dirichlet particle at all: the pure Neumann problem fixes p only up to a constant;
  // p = 0 at the fluid particle with the smallest id fixes it (the first of a serial run's
  // order, and the same particle however the processes share the fluid).
  pinned = surface == 0;
  std::size_t pin = n;
  if (pinned) {
    for (std::size_t i = 0; i < owned; ++i)
      if (pin == n || P.id[i] < P.id[pin]) pin = i;
    if (dist) {
      const double smallest = -dist->max(pin < n ? -static_cast<double>(P.id[pin]) : -1e300);
      if (pin < n && static_cast<double>(P.id[pin]) != smallest) pin = n;
    }
  }
  for (std::size_t i = 0; i < owned; ++i) {
    if (i == pin || onSurface(i)) continue;
    unknown_of[i] = static_cast<int>(particle_of.size());
    particle_of.push_back(static_cast<int>(i));
  }
  count = columns = particle_of.size();
  global_count = count;
  if (!dist) return;
  // Global numbers: this process's rows follow those of the processes before it; the ghosts
  // take their owners' numbers (-1: not an unknown) and become the further columns.
  const std::vector<double> counts = dist->allGather(std::vector<double>{static_cast<double>(count)});
  std::uint64_t first = 0;
  global_count = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    if (static_cast<int>(r) < dist->rank()) first += static_cast<std::uint64_t>(counts[r]);
    global_count += static_cast<std::uint64_t>(counts[r]);
  }
  global_number_.assign(n, -1.0);
  for (std::size_t r = 0; r < count; ++r) global_number_[static_cast<std::size_t>(particle_of[r])] = static_cast<double>(first + r);
  const HaloArray numbers{global_number_.data(), 1, Field::Range::moving};
  dist->refreshArrays(std::span<const HaloArray>(&numbers, 1));
  across.communicator = dist->communicator();
  across.first_row = static_cast<std::int64_t>(first);
  across.global_rows = static_cast<std::int64_t>(global_count);
  across.column_global.resize(count);
  for (std::size_t c = 0; c < count; ++c) across.column_global[c] = static_cast<std::int64_t>(first + c);
  for (std::size_t i = owned; i < n; ++i) {
    if (global_number_[i] < 0) continue;
    unknown_of[i] = static_cast<int>(columns++);
    across.column_global.push_back(static_cast<std::int64_t>(global_number_[i]));
  }
}

template <int D>
double PressureUnknowns::rms(const std::vector<double>& per_particle, ParticleDistribution<D>* dist) const {
  double sum2 = 0;
  for (std::size_t r = 0; r < count; ++r) {
    const double d = per_particle[static_cast<std::size_t>(particle_of[r])];
    sum2 += d * d;
  }
  if (dist) sum2 = dist->sum(sum2);
  return global_count ? std::sqrt(sum2 / static_cast<double>(global_count)) : 0.0;
}

template <int D>
void continuityDivergence(StepContext<D>& sys, const WallFlux<D>& walls, std::vector<double>& out) {
  const ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.n_moving;
  out.resize(n);
  const double* v = P.velocity.data();
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  const Vec<D> wall_shift = walls.shift;
  sys.driver.forEachMoving(P, sys.kernel, sys.domain, sys.neighbours, false,
                           [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                             double acc = 0;
                             for (const Neighbour<D>& nb : moving) {
                               double d = 0;
                               for (int a = 0; a < D; ++a) d += (v[D * i + a] - v[D * nb.j + a]) * nb.rij[a];
                               acc += m[nb.j] * d * nb.F;
                             }
                             for (const Neighbour<D>& nb : fixed) {
                               Vec<D> u;
                               for (int a = 0; a < D; ++a) u[a] = v[D * i + a] - v[D * nb.j + a] - wall_shift[a];
                               // no_penetration: the normal flux into the wall is the walls'
                               // Neumann data (wall_conditions.cpp), not a source
                               if (walls.normal_flux_removed) {
                                 const Vec<D>& normal = (*walls.normal_flux_removed)[i];
                                 u -= u.dot(normal) * normal;
                               }
                               // the velocity inlet: the flux along the flow through the buffer
                               // is the buffer's Neumann data (wall_conditions.cpp)
                               if (walls.inlet && P.kind[nb.j] == static_cast<std::uint8_t>(ParticleKind::inflow)) {
                                 const Vec<D>& e = walls.inlet->direction;
                                 u -= u.dot(e) * e;
                               }
                               acc += m[nb.j] * u.dot(nb.rij) * nb.F;
                             }
                             out[i] = -acc / rho[i];
                           });
}

template <int D>
void GradientRows<D>::build(StepContext<D>& sys, GradientForm form, WallPressures walls) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  // Rows of the owned particles (a distributed run's ghosts take their owners' results), laid
  // out over every moving particle's list.
  const std::size_t n = P.ownedMoving();
  const std::size_t entries = list.start[P.n_moving] + P.n_moving;
  index.resize(entries);
  coef.resize(entries);
  const CandidatePairs<D> pairs(P, sys.kernel, sys.domain, list);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  const bool walls_enter = walls == WallPressures::enter;
  using Mat = Eigen::Matrix<double, D, D>;
  const int threads = n >= kParallelMinimum ? omp_get_max_threads() : 1;
  if (pairs_.size() < static_cast<std::size_t>(threads)) pairs_.resize(static_cast<std::size_t>(threads));
  sys.kernel.visit([&](auto shape) {
#pragma omp parallel num_threads(threads)
    {
      std::vector<PairGeometry>& inside = pairs_[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
      for (std::size_t k = 0; k < n; ++k) {
        const std::size_t e0 = list.start[k] + k;
        // entry e of k's row for the list entry c: e0 + 1 + (c - start[k])
        const std::size_t shift = e0 + 1 - list.start[k];
        // The pairs inside the support (their geometry evaluated once); the candidates outside
        // it get coefficient 0.
        inside.clear();
        pairs.visit(
            shape, k, list.start[k], list.start[k + 1],
            [&](std::size_t c, std::size_t j, const Vec<D>& rkj, double, double F) {
              inside.push_back({c + shift, j, rkj, F});
            },
            [&](std::size_t c) {
              const std::size_t e = c + shift;
              index[e] = static_cast<Index>(list.nbr[c]);
              coef[e].setZero();
            });
        // Renormalisation M_k = -sum_j V_j F r r^T (identity for the plain forms).
        Mat Minv = Mat::Identity();
        if (form == GradientForm::renormalised) {
          Mat M = Mat::Zero();
          for (const PairGeometry& g : inside) M -= (m[g.j] / rho[g.j] * g.F) * g.rkj * g.rkj.transpose();
          Minv = renormalisationInverse<D>(M);
        }
        Vec<D> self = Vec<D>::Zero();
        const double rhok = rho[k];
        for (const PairGeometry& g : inside) {
          const std::size_t j = g.j;
          index[g.entry] = static_cast<Index>(j);
          if (form == GradientForm::symmetric) {  // thesis eq. (3.18)
            coef[g.entry] = walls_enter || j < P.n_moving ? Vec<D>((m[j] / (rho[j] * rho[j]) * g.F) * g.rkj) : Vec<D>::Zero();
            self += (m[j] / (rhok * rhok) * g.F) * g.rkj;
          } else {  // thesis eq. (3.17), renormalised or not
            coef[g.entry] = (m[j] / rho[j] * g.F / rhok) * (Minv * g.rkj);
            self -= coef[g.entry];
          }
        }
        index[e0] = static_cast<Index>(k);
        coef[e0] = self;
      }
    }
  });
}

template <int D>
void PressureSystem<D>::assemble(StepContext<D>& sys, double dt, LaplacianForm form, const PressureUnknowns& unknowns,
                                 const GradientRows<D>& gradient, const WallConditions<D>& walls,
                                 const std::vector<double>& divergence, const double* carried, AssembledMatrix& out,
                                 const double* known) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving, rows = unknowns.count, columns = unknowns.columns;
  rhs_.resize(static_cast<Eigen::Index>(rows));
  const int threads = rows >= kParallelMinimum ? omp_get_max_threads() : 1;
  if (rows_.size() < static_cast<std::size_t>(threads)) rows_.resize(static_cast<std::size_t>(threads));
  const CandidatePairs<D> pairs(P, sys.kernel, sys.domain, list);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  const double inv_dt = 1.0 / dt;
  const bool consistent = form == LaplacianForm::consistent;
  const bool exact = form == LaplacianForm::exact;
  const std::vector<int>& unknown_of = unknowns.unknown_of;
  const std::vector<int>& particle_of = unknowns.particle_of;
  const std::vector<Index>& g_index = gradient.index;
  const std::vector<Vec<D>>& g_coef = gradient.coef;
  const std::vector<double>& wall_weight = walls.weights();
  const std::vector<double>& wall_offset = walls.offsets();
  // Exact rows are weighted by the particle volume V_i (relative to the mean), which makes the
  // matrix V div_h G = D M^-1 D^T V-weighted symmetric (divergence_cleaning.cpp).
  double mean_volume = 0;
  if (exact) {
    for (std::size_t r = 0; r < rows; ++r) mean_volume += m[particle_of[r]] / rho[particle_of[r]];
    mean_volume = rows ? mean_volume / static_cast<double>(rows) : 1.0;
  }
  const double rho0 = rho0_;

  sys.kernel.visit([&](auto shape) {
#pragma omp parallel num_threads(threads)
    {
      const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
      const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
      RowBuffer& rb = rows_[t];
      if (rb.slot.size() < columns) rb.slot.assign(columns, -1);
      rb.cols.clear();
      rb.vals.clear();
      rb.lengths.clear();
      const std::size_t r0 = rows * t / nt, r1 = rows * (t + 1) / nt;
      // Sort the row by column (the values follow through the slots, which are then reset).
      auto finishRow = [&](std::size_t row_begin) {
        const std::size_t len = rb.cols.size() - row_begin;
        rb.row_vals.assign(rb.vals.begin() + static_cast<std::ptrdiff_t>(row_begin), rb.vals.end());
        std::sort(rb.cols.begin() + static_cast<std::ptrdiff_t>(row_begin), rb.cols.end());
        for (std::size_t q = row_begin; q < rb.cols.size(); ++q) {
          int& s = rb.slot[static_cast<std::size_t>(rb.cols[q])];
          rb.vals[q] = rb.row_vals[static_cast<std::size_t>(s) - row_begin];
          s = -1;
        }
        rb.lengths.push_back(static_cast<int>(len));
      };
      for (std::size_t r = r0; r < r1; ++r) {
        const std::size_t i = static_cast<std::size_t>(particle_of[r]);
        const std::size_t row_begin = rb.cols.size();
        double constant = 0;  // the wall pressures' hydrostatic parts and the known pressures, moved to the right side
        double l_old = 0;     // incremental form: the operator applied to the last pressure
        auto column = [&](int u, double value) {
          int& s = rb.slot[static_cast<std::size_t>(u)];
          if (s < 0) {
            s = static_cast<int>(rb.cols.size());
            rb.cols.push_back(u);
            rb.vals.push_back(value);
          } else {
            rb.vals[static_cast<std::size_t>(s)] += value;
          }
        };
        // value * p_q, q a fluid particle (an unknown, or known: p = 0 or the surface's value)
        // or a wall particle (p_w eliminated: sum_f c_wf p_f + b_w).
        auto add = [&](std::size_t q, double value) {
          if (carried) l_old += value * carried[q];
          if (q < n) {
            if (unknown_of[q] >= 0)
              column(unknown_of[q], value);
            else if (known)
              constant += value * known[q];
            return;
          }
          constant += value * wall_offset[q - n];
          for (std::size_t kk = list.start[q]; kk < list.split[q]; ++kk) {
            const double c = wall_weight[kk];
            if (c == 0.0) continue;
            const std::size_t f = list.nbr[kk];
            const int u = unknown_of[f];
            if (u >= 0)
              column(u, value * c);
            else if (known)
              constant += value * c * known[f];
          }
        };
        column(static_cast<int>(r), 0.0);  // the diagonal is always stored
        if (exact) {
          // -rho_i div_h(G p)_i = -rho_i div(v*)_i / dt with the divergence of the continuity
          // equation applied to the corrected velocities (walls keep theirs):
          //   -rho_i div_h(u)_i = u_i . sum_j m_j F_ij r_ij - sum_{j moving} m_j F_ij r_ij . u_j,
          // u_k = (G p)_k through the gradient row of k: two kernel supports wide.
          // Row i times rho0 V_i / (rho_i V_mean): the matrix is then symmetric.
          const double w = rho0 * m[i] / (rho[i] * rho[i] * mean_volume);
          Vec<D> self = Vec<D>::Zero();
          pairs.visit(shape, i, list.start[i], list.start[i + 1],
                      [&](std::size_t, std::size_t j, const Vec<D>& rij, double, double F) {
                        const Vec<D> a = (w * m[j] * F) * rij;
                        self += a;
                        if (j >= n) return;
                        for (std::size_t e = list.start[j] + j, e1 = list.start[j + 1] + j + 1; e < e1; ++e) {
                          const double v = -a.dot(g_coef[e]);
                          if (v != 0.0) add(g_index[e], v);
                        }
                      });
          for (std::size_t e = list.start[i] + i, e1 = list.start[i + 1] + i + 1; e < e1; ++e) {
            const double v = self.dot(g_coef[e]);
            if (v != 0.0) add(g_index[e], v);
          }
          rhs_[static_cast<Eigen::Index>(r)] = -w * rho[i] * divergence[i] * inv_dt + (l_old - constant);
          finishRow(row_begin);
          continue;
        }
        // sum_j k_ij (p_i - p_j) [- zeta_i . grad p_i] = -rho_i div(v*)_i / dt,
        // k_ij = -8 rho_i m_j F_ij / (rho_i + rho_j)^2 > 0, zeta_i = sum_j k_ij r_ij (above).
        Vec<D> zeta = Vec<D>::Zero();
        double trace_m = 0;  // tr M_i = -sum_j V_j F_ij r_ij^2 (D on a full support)
        pairs.visit(shape, i, list.start[i], list.start[i + 1],
                    [&](std::size_t, std::size_t j, const Vec<D>& rij, double, double F) {
                      const double s = rho[i] + rho[j];
                      const double kij = -8.0 * rho[i] * m[j] * F / (s * s);
                      add(i, kij);
                      add(j, -kij);
                      zeta += kij * rij;
                      trace_m -= m[j] / rho[j] * F * rij.squaredNorm();
                    });
        if (consistent) {
          // grad p_i = rho_i (G p)_i through the gradient row of i
          zeta *= -rho[i];
          const std::size_t e0 = list.start[i] + i, e1 = list.start[i + 1] + i + 1;
          for (std::size_t e = e0; e < e1; ++e) {
            const double v = zeta.dot(g_coef[e]);
            if (v != 0.0) add(g_index[e], v);
          }
        }
        // Consistent form: the operator scaled by D / tr M_i, so that it measures the second
        // derivatives with the weight of a full support also where the support is truncated
        // (near the free surface the plain sum is about half as large, and the projection
        // over-corrected there: an instability of the surface rows, docs/theory.md).
        const double scale = consistent && trace_m > 0 ? D / trace_m : 1.0;
        if (scale != 1.0)
          for (std::size_t q = row_begin; q < rb.vals.size(); ++q) rb.vals[q] *= scale;
        rhs_[static_cast<Eigen::Index>(r)] = -rho[i] * divergence[i] * inv_dt + scale * (l_old - constant);
        finishRow(row_begin);
      }
    }
  });

  // Gather the rows (threads hold consecutive row ranges) into the compressed matrix.
  std::size_t nnz = 0;
  for (int t = 0; t < threads; ++t) nnz += rows_[static_cast<std::size_t>(t)].cols.size();
  SparseRowMatrix& matrix = out.matrix;
  matrix.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(columns));
  matrix.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* outer = matrix.outerIndexPtr();
  int* inner = matrix.innerIndexPtr();
  double* val = matrix.valuePtr();
  std::size_t r = 0, e = 0;
  outer[0] = 0;
  for (int t = 0; t < threads; ++t) {
    const RowBuffer& rb = rows_[static_cast<std::size_t>(t)];
    std::copy(rb.cols.begin(), rb.cols.end(), inner + e);
    std::copy(rb.vals.begin(), rb.vals.end(), val + e);
    for (int len : rb.lengths) {
      e += static_cast<std::size_t>(len);
      outer[++r] = static_cast<int>(e);
    }
  }
  if (exact) {
    // The exact operator is singular along the pressure modes that the gradient annihilates
    // (checkerboards on a regular lattice). Those modes do not move the velocity, and the
    // source has no component along them up to round-off, which the solvers cannot reach: a
    // relative shift of the diagonal makes the matrix definite and changes the corrected
    // velocity's divergence by about the shift (docs/theory.md §10).
    for (std::size_t q = 0; q < rows; ++q) matrix.coeffRef(static_cast<Eigen::Index>(q), static_cast<Eigen::Index>(q)) *= 1.0 + kExactShift;
  }
  out.pattern_changed = out.outer.size() != rows + 1 || out.inner.size() != nnz ||
                        !std::equal(out.outer.begin(), out.outer.end(), outer) ||
                        !std::equal(out.inner.begin(), out.inner.end(), inner);
  if (out.pattern_changed) {
    out.outer.assign(outer, outer + rows + 1);
    out.inner.assign(inner, inner + nnz);
    ++out.pattern_builds;
  }
}

template <int D>
void correctVelocities(StepContext<D>& sys, const ProjectionOperators<D>& ops, double dt, double* y, const double* p,
                       const double* p_old) {
  ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.ownedMoving();  // the state's particles
  double* yv = y + n * (D + 1);
  std::vector<double>& correction = ops.correction;
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t k = 0; k < n; ++k) {
    const Vec<D> a = ops.gradient.at(list, k, p, p_old);
    for (int c = 0; c < D; ++c) {
      yv[D * k + c] -= dt * a[c];
      P.velocity[D * k + c] = yv[D * k + c];
      correction[D * k + c] += a[c];
    }
  }
}

#define VESPH_INSTANTIATE_PRESSURE_SYSTEM(D)                                                                  \
  template void PressureUnknowns::number<D>(const ParticleSet<D>&, const double*, ParticleDistribution<D>*);    \
  template double PressureUnknowns::rms<D>(const std::vector<double>&, ParticleDistribution<D>*) const;         \
  template void continuityDivergence<D>(StepContext<D>&, const WallFlux<D>&, std::vector<double>&);             \
  template struct GradientRows<D>;                                                                             \
  template class PressureSystem<D>;                                                                            \
  template void correctVelocities<D>(StepContext<D>&, const ProjectionOperators<D>&, double, double*, const double*, \
                                     const double*);
VESPH_INSTANTIATE_PRESSURE_SYSTEM(2)
VESPH_INSTANTIATE_PRESSURE_SYSTEM(3)
#undef VESPH_INSTANTIATE_PRESSURE_SYSTEM

}  // namespace vesph::isph
