// The ISPH projection hook; the method, its equations and references are in
// include/vesph/isph/projection.hpp.
#include "vesph/isph/projection.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "vesph/boundary/inflow_outflow.hpp"
#include "vesph/core/renormalisation.hpp"

#include "vesph/sim/system.hpp"

namespace vesph {
namespace {

using Clock = std::chrono::steady_clock;
// Relative diagonal shift of the exact projection's matrix (assemble()).
constexpr double kExactShift = 1e-10;
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

// The pair geometry of a neighbour-list candidate (the candidate list holds pairs out to the
// support plus the skin). The assembly visits candidates itself, not through the pair driver,
// because the gradient rows and the wall weights are stored by neighbour-list entry (a fixed
// layout, allocated once per list build) and a row needs the lists of its neighbours too.
// Returns false outside the support.
template <int D>
struct CandidateGeometry {
  const double* x;
  const Domain<D>* domain;
  double cut2, inv_h, w_scale, f_scale;

  template <class Shape>
  bool operator()(Shape, std::size_t i, std::size_t j, Vec<D>& rij, double& W, double& F) const {
    double r2 = 0;
    for (int a = 0; a < D; ++a) {
      rij[a] = domain->image(a, x[D * i + a] - x[D * j + a]);
      r2 += rij[a] * rij[a];
    }
    if (r2 >= cut2 || r2 == 0.0) return false;
    const double q = std::sqrt(r2) * inv_h;
    W = w_scale * Shape::f(q);
    F = f_scale * Shape::df_over_q(q);
    return true;
  }
};

template <int D>
CandidateGeometry<D> candidateGeometry(const SphSystem<D>& sys) {
  const Kernel& k = sys.kernel;
  return {sys.particles.position.data(), &sys.domain, k.supportRadius() * k.supportRadius(), 1.0 / k.h, k.w_scale,
          k.dw_scale / k.h};
}

}  // namespace

template <int D>
Projection<D>::Projection(ConfigTable& cfg) {
  options_ = readLinearSolverOptions(cfg);
  consistent_ = cfg.choice("laplacian", "consistent", {"consistent", "morris"}) == "consistent";
  const std::string g = cfg.choice("gradient", "renormalised", {"renormalised", "difference", "symmetric"});
  gradient_ = g == "renormalised" ? Gradient::renormalised : g == "difference" ? Gradient::difference : Gradient::symmetric;
  predictor_ = cfg.choice("carried_pressure", "increment", {"increment", "predictor"}) == "predictor";
  no_penetration_ = cfg.choice("wall_condition", "hydrostatic", {"hydrostatic", "no_penetration"}) == "no_penetration";
  velocity_inlet_ = cfg.choice("inlet_condition", "zero_gradient", {"zero_gradient", "velocity"}) == "velocity";
  if (cfg.has("density_relaxation_time"))
    density_relaxation_time_ = cfg.number("density_relaxation_time", std::nullopt, Bound::positive, "s");
  cleaning_ = cfg.boolean("divergence_cleaning", false);
  if (cleaning_) {
    // Direct solvers only: the matrix is near-singular (header), and conjugate gradients did
    // not reach 1e-8 in 5000 iterations on the 1520 unknowns of the hydrostatic tank.
    cleaning_options_.type = cfg.choice("cleaning_solver", "umfpack", {"umfpack", "klu"});
    cleaning_solver_ = makeLinearSolver(cleaning_options_);
  } else {
    if (cfg.has("cleaning_solver")) cfg.fail("cleaning_solver", "only with divergence_cleaning = true");
  }
  if (cleaning_ && density_relaxation_time_ > 0)
    cfg.fail("density_relaxation_time", "absent with divergence_cleaning = true (the exact projection would remove the "
                                        "divergence the relaxation asks for)");
  solver_ = makeLinearSolver(options_);
}

template <int D>
void Projection<D>::setup(Setup<D>& s) {
  struct Forbidden {
    const char* effect;
    const char* why;
  };
  for (const Forbidden& f :
       {Forbidden{"equation_of_state", "ISPH takes the pressure from the Poisson equation, not from an equation of state"},
        Forbidden{"continuity", "ISPH particles keep their density (the projection keeps the velocity divergence-free)"}})
    if (s.find(f.effect))
      throw InputError(std::string("effects.") + f.effect + ": not with solver.scheme = \"isph\" (" + f.why +
                       "); remove it, or use scheme = \"wcsph\"");
  pressure_ = &s.particles.fields.require("pressure", 1, Field::Range::all);
  has_free_surface_ = s.find("free_surface") != nullptr;
  // With [effects.pressure_gradient] the right-hand side carries the last projection's
  // pressure through the step, and the projection corrects it (incremental form, header).
  incremental_ = s.find("pressure_gradient") != nullptr;
  if (predictor_ && !incremental_)
    throw InputError("solver.carried_pressure = \"predictor\" needs [effects.pressure_gradient] (the pressure the "
                     "right-hand side carries); without it every projection solves for the whole pressure anyway");
  if (velocity_inlet_ && incremental_ && !predictor_)
    throw InputError("solver.inlet_condition = \"velocity\" is not implemented with the incremental form "
                     "(carried_pressure = \"increment\"): the inlet's push would be carried on into the next steps; use "
                     "carried_pressure = \"predictor\" (docs/theory.md §10)");
  if (no_penetration_ && incremental_ && !predictor_)
    throw InputError("solver.wall_condition = \"no_penetration\" is not implemented with the incremental form "
                     "(carried_pressure = \"increment\"): the push would be carried on into the next steps; use "
                     "carried_pressure = \"predictor\" (docs/theory.md §10)");
  if (density_relaxation_time_ > 0) {
    if (!has_free_surface_)
      throw InputError("solver.density_relaxation_time needs [effects.free_surface] (its number density is the "
                       "particles' spacing the term relaxes)");
    lattice_number_density_ = s.kernel.latticeSum(s.spacing);
  }
  g_ = s.body_acceleration;
  rho0_ = s.rest_density;
}

template <int D>
void Projection<D>::flagFreeSurface(SphSystem<D>& sys, double t) {
  if (!free_surface_effect_) {
    for (auto& e : sys.effects)
      if (e->name() == "free_surface") free_surface_effect_ = e.get();
    surface_flag_ = sys.particles.fields.find("free_surface");
  }
  if (!free_surface_effect_) return;
  const RhsContext<D> ctx{sys.particles, sys.kernel, sys.domain, t, nullptr, nullptr, nullptr, nullptr};
  Effect<D>* e = free_surface_effect_;
  sys.driver.run(ctx, sys.neighbours, std::span<Effect<D>* const>(&e, 1));
}

template <int D>
void Projection<D>::numberUnknowns(const SphSystem<D>& sys) {
  const std::size_t n = sys.particles.n_moving;
  unknown_of_.assign(n, -1);
  particle_of_.clear();
  std::size_t surface = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (surface_flag_ && surface_flag_->data[i] > 0.5) ++surface;
  // No Dirichlet particle at all: the pure Neumann problem fixes p only up to a constant;
  // p = 0 at the first fluid particle fixes it.
  pinned_ = surface == 0;
  for (std::size_t i = pinned_ ? 1 : 0; i < n; ++i) {
    if (surface_flag_ && surface_flag_->data[i] > 0.5) continue;
    unknown_of_[i] = static_cast<int>(particle_of_.size());
    particle_of_.push_back(static_cast<int>(i));
  }
  n_unknowns_ = particle_of_.size();
}

template <int D>
void Projection<D>::wallNormals(SphSystem<D>& sys) {
  // n_i = -sum_w V_w grad_i W_iw / |.|: away from the wall particles in i's support (for a
  // particle over a flat wall the wall's normal, also at the edge of a spreading film, where the
  // wall extends on both sides of it; at a corner the bisector). Zero without wall neighbours.
  // gap_i: how far i may still approach the walls before it reaches the rest distance of the
  // lattice (half a spacing above the wall surface, i.e. one spacing from the first wall row).
  const ParticleSet<D>& P = sys.particles;
  wall_normal_.assign(P.n_moving, Vec<D>::Zero());
  wall_gap_.assign(P.n_moving, 0.0);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  sys.driver.forEachMoving(P, sys.kernel, sys.domain, sys.neighbours, false,
                           [&](Index i, std::span<const Neighbour<D>>, std::span<const Neighbour<D>> fixed) {
                             Vec<D> s = Vec<D>::Zero();
                             for (const Neighbour<D>& nb : fixed) s -= (m[nb.j] / rho[nb.j] * nb.F) * nb.rij;
                             const double norm = s.norm();
                             if (norm == 0) return;
                             const Vec<D> n = s / norm;
                             wall_normal_[i] = n;
                             double nearest = std::numeric_limits<double>::infinity();
                             for (const Neighbour<D>& nb : fixed) nearest = std::min(nearest, n.dot(nb.rij));
                             const double spacing = std::pow(m[i] / rho[i], 1.0 / D);
                             wall_gap_[i] = std::max(0.0, nearest - spacing);
                           });
}

template <int D>
void Projection<D>::wallExtrapolation(const SphSystem<D>& sys, double dt, bool inlet_data) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving, N = P.size();
  wall_weight_.resize(list.nbr.size());
  wall_offset_.assign(N - n, 0.0);
  const CandidateGeometry<D> geo = candidateGeometry(sys);
  const Vec<D> rho_g = rho0_ * g_;
  // inlet_data: across the flow the buffer is a hydrostatic wall (the source shifts it by dt g
  // like the walls); along e the body force's share dt g.e is in u_f already.
  const Vec<D> rho_g_across = rho_g - rho_g.dot(inflow_direction_) * inflow_direction_;
  const double* v = P.velocity.data();
  sys.kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static) if (N - n >= kParallelMinimum)
    for (std::size_t w = n; w < N; ++w) {
      double sumW = 0, offset = 0, push = 0;  // offset: hydrostatic; push: no_penetration
      double inlet = 0;                       // inlet_condition = "velocity": the buffer's Neumann data
      const bool buffer = inlet_data && P.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow);
      Vec<D> rij;
      double W, F;
      for (std::size_t k = list.start[w]; k < list.split[w]; ++k) {
        const std::size_t f = list.nbr[k];
        if (geo(shape, w, f, rij, W, F)) {
          wall_weight_[k] = W;
          sumW += W;
          if (buffer) {
            // The fluid's velocity along the flow relative to the buffer's: the pressure step
            // rho0 (u_f - u_w).e (e . r_wf) / dt over f's makes -dt G p bring the rows next to
            // the buffer to its speed (header, inlet_condition).
            double ue = 0;
            for (int a = 0; a < D; ++a) ue += (v[D * f + a] - v[D * w + a]) * inflow_direction_[a];
            inlet += rho0_ * ue * inflow_direction_.dot(rij) * W;
            offset += rho_g_across.dot(rij) * W;
            continue;
          }
          if (!no_penetration_) {
            offset += rho_g.dot(rij) * W;  // rij = r_w - r_f
          } else {
            // The normal velocity of f relative to the wall beyond what closes its gap within
            // dt: delta < 0 is an approach the correction must stop, and the wall pressure
            // rho0 delta (n_f . r_wf) / dt above f's does (header, step 2). Only a push: the
            // walls do not hold the fluid back where it moves away.
            const Vec<D>& nf = wall_normal_[f];
            double un = 0;
            for (int a = 0; a < D; ++a) un += (v[D * f + a] - v[D * w + a]) * nf[a];
            const double delta = un + wall_gap_[f] / dt;
            push += rho0_ * std::min(delta, 0.0) * nf.dot(rij) * W;
          }
        } else {
          wall_weight_[k] = 0.0;
        }
      }
      const double inv = sumW > 0 ? 1.0 / sumW : 0.0;
      for (std::size_t k = list.start[w]; k < list.split[w]; ++k) wall_weight_[k] *= inv;
      // Without no_penetration: the hydrostatic part (Adami et al. eq. 27). With it, the push
      // alone: the velocity it answers (v* of the plain form, v** of the predictor form)
      // carries dt g, so the hydrostatic part is in it.
      wall_offset_[w - n] = buffer ? (inlet / dt + offset) * inv : no_penetration_ ? push * inv / dt : offset * inv;
    }
  });
}

template <int D>
void Projection<D>::wallsAndSource(SphSystem<D>& sys, double dt, bool whole_pressure, bool inlet_data) {
  // The walls' Neumann data and the source divergence of the velocity in P.velocity (header,
  // step 2). Solving for the whole pressure (plain and predictor forms, the initial pressure),
  // the hydrostatic wall offsets answer the body force's share dt g of that velocity, so the
  // walls enter the source moving with u_w + dt g; solving for the increment, the offsets of
  // p^{n+1} and p^n cancel and the walls enter at rest (divergence_ then holds the divergence
  // computed for the report). no_penetration: the normal velocity is in the wall offsets and
  // the walls' normal flux leaves the source.
  if (no_penetration_) wallNormals(sys);
  // The inlet's velocity data in the steps' solves only (inlet_data): the initial solve
  // (start) has an acceleration, not a velocity, in P.velocity. (inlet_condition = "velocity"
  // is refused with the incremental form, so those solves are for the whole pressure.)
  const bool inlet = velocity_inlet_ && inlet_data;
  if (inlet && inflow_direction_.isZero()) {
    // The scene has a prescribed inflow buffer (checked at setup, src/sim/simulation.cpp); its
    // direction does not change.
    for (const auto& h : sys.hooks)
      if (const auto* flow = dynamic_cast<const InflowOutflow<D>*>(h.get()); flow && flow->hasBuffer())
        inflow_direction_ = flow->flowDirection();
  }
  wallExtrapolation(sys, dt, inlet);
  if (no_penetration_)
    divergence(sys, Vec<D>::Zero(), true, inlet);
  else if (whole_pressure)
    divergence(sys, Vec<D>(dt * g_), false, inlet);
}

template <int D>
double Projection<D>::divergence(SphSystem<D>& sys, const Vec<D>& wall_shift, bool tangential_walls, bool inlet_data) {
  const ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.n_moving;
  divergence_.resize(n);
  const double* v = P.velocity.data();
  const double* m = P.mass.data();
  const double* rho = P.density.data();
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
                               // Neumann data (wallExtrapolation), not a source
                               if (tangential_walls) u -= u.dot(wall_normal_[i]) * wall_normal_[i];
                               // inlet_condition = "velocity": the flux along the flow through
                               // the buffer is the buffer's Neumann data (wallExtrapolation)
                               if (inlet_data && P.kind[nb.j] == static_cast<std::uint8_t>(ParticleKind::inflow))
                                 u -= u.dot(inflow_direction_) * inflow_direction_;
                               acc += m[nb.j] * u.dot(nb.rij) * nb.F;
                             }
                             divergence_[i] = -acc / rho[i];
                           });
  double sum2 = 0;
  for (std::size_t r = 0; r < n_unknowns_; ++r) {
    const double d = divergence_[static_cast<std::size_t>(particle_of_[r])];
    sum2 += d * d;
  }
  return n_unknowns_ ? std::sqrt(sum2 / static_cast<double>(n_unknowns_)) : 0.0;
}

template <int D>
void Projection<D>::gradientRows(SphSystem<D>& sys, Gradient form, bool walls_enter) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving;
  const std::size_t entries = list.start[n] + n;
  g_index_.resize(entries);
  g_coef_.resize(entries);
  const CandidateGeometry<D> geo = candidateGeometry(sys);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  using Mat = Eigen::Matrix<double, D, D>;
  sys.kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t e0 = list.start[k] + k;
      Vec<D> rkj;
      double W, F;
      // Renormalisation M_k = -sum_j V_j F r r^T (identity for the plain forms).
      Mat Minv = Mat::Identity();
      if (form == Gradient::renormalised) {
        Mat M = Mat::Zero();
        for (std::size_t c = list.start[k]; c < list.start[k + 1]; ++c) {
          const std::size_t j = list.nbr[c];
          if (geo(shape, k, j, rkj, W, F)) M -= (m[j] / rho[j] * F) * rkj * rkj.transpose();
        }
        Minv = renormalisationInverse<D>(M);
      }
      Vec<D> self = Vec<D>::Zero();
      const double rhok = rho[k];
      for (std::size_t c = list.start[k]; c < list.start[k + 1]; ++c) {
        const std::size_t j = list.nbr[c];
        const std::size_t e = e0 + 1 + (c - list.start[k]);
        g_index_[e] = static_cast<Index>(j);
        if (!geo(shape, k, j, rkj, W, F)) {
          g_coef_[e].setZero();
          continue;
        }
        if (form == Gradient::symmetric) {  // thesis eq. (3.18)
          g_coef_[e] = walls_enter || j < n ? Vec<D>((m[j] / (rho[j] * rho[j]) * F) * rkj) : Vec<D>::Zero();
          self += (m[j] / (rhok * rhok) * F) * rkj;
        } else {  // thesis eq. (3.17), renormalised or not
          g_coef_[e] = (m[j] / rho[j] * F / rhok) * (Minv * rkj);
          self -= g_coef_[e];
        }
      }
      g_index_[e0] = static_cast<Index>(k);
      g_coef_[e0] = self;
    }
  });
}

template <int D>
void Projection<D>::assemble(SphSystem<D>& sys, double dt, Laplacian op, bool incremental, Assembled& out) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving, rows = n_unknowns_;
  rhs_.resize(static_cast<Eigen::Index>(rows));
  const int threads = rows >= kParallelMinimum ? omp_get_max_threads() : 1;
  if (rows_.size() < static_cast<std::size_t>(threads)) rows_.resize(static_cast<std::size_t>(threads));
  const CandidateGeometry<D> geo = candidateGeometry(sys);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  const double inv_dt = 1.0 / dt;
  const bool consistent = op == Laplacian::consistent;
  const bool exact = op == Laplacian::exact;
  // Exact rows are weighted by the particle volume V_i (relative to the mean), which makes the
  // matrix V div_h G = D M^-1 D^T V-weighted symmetric (header).
  double mean_volume = 0;
  if (exact) {
    for (std::size_t r = 0; r < rows; ++r) mean_volume += m[particle_of_[r]] / rho[particle_of_[r]];
    mean_volume = rows ? mean_volume / static_cast<double>(rows) : 1.0;
  }
  const double* p_old = pressure_->data.data();  // the last projection's pressure (walls too)
  const double rho0 = rho0_;

  sys.kernel.visit([&](auto shape) {
#pragma omp parallel num_threads(threads)
    {
      const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
      const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
      RowBuffer& rb = rows_[t];
      if (rb.slot.size() < rows) rb.slot.assign(rows, -1);
      rb.cols.clear();
      rb.vals.clear();
      rb.lengths.clear();
      std::vector<std::pair<int, double>> sorted;
      const std::size_t r0 = rows * t / nt, r1 = rows * (t + 1) / nt;
      // Sort the row by column; reset the slots.
      auto finishRow = [&](std::size_t row_begin) {
        const std::size_t len = rb.cols.size() - row_begin;
        sorted.resize(len);
        for (std::size_t q = 0; q < len; ++q) {
          sorted[q] = {rb.cols[row_begin + q], rb.vals[row_begin + q]};
          rb.slot[static_cast<std::size_t>(rb.cols[row_begin + q])] = -1;
        }
        std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        for (std::size_t q = 0; q < len; ++q) {
          rb.cols[row_begin + q] = sorted[q].first;
          rb.vals[row_begin + q] = sorted[q].second;
        }
        rb.lengths.push_back(static_cast<int>(len));
      };
      for (std::size_t r = r0; r < r1; ++r) {
        const std::size_t i = static_cast<std::size_t>(particle_of_[r]);
        const std::size_t row_begin = rb.cols.size();
        double constant = 0;  // the wall pressures' hydrostatic parts, moved to the right side
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
        // value * p_q, q a fluid particle (an unknown, or p = 0) or a wall particle (p_w
        // eliminated: sum_f c_wf p_f + b_w).
        auto add = [&](std::size_t q, double value) {
          if (incremental) l_old += value * p_old[q];
          if (q < n) {
            if (unknown_of_[q] >= 0) column(unknown_of_[q], value);
            return;
          }
          constant += value * wall_offset_[q - n];
          for (std::size_t kk = list.start[q]; kk < list.split[q]; ++kk) {
            const double c = wall_weight_[kk];
            const int u = unknown_of_[list.nbr[kk]];
            if (c != 0.0 && u >= 0) column(u, value * c);
          }
        };
        column(static_cast<int>(r), 0.0);  // the diagonal is always stored
        Vec<D> rij;
        double W, F;
        if (exact) {
          // -rho_i div_h(G p)_i = -rho_i div(v*)_i / dt with the divergence of the continuity
          // equation applied to the corrected velocities (walls keep theirs):
          //   -rho_i div_h(u)_i = u_i . sum_j m_j F_ij r_ij - sum_{j moving} m_j F_ij r_ij . u_j,
          // u_k = (G p)_k through the gradient row of k: two kernel supports wide.
          // Row i times rho0 V_i / (rho_i V_mean): the matrix is then symmetric (header).
          const double w = rho0 * m[i] / (rho[i] * rho[i] * mean_volume);
          Vec<D> self = Vec<D>::Zero();
          for (std::size_t c = list.start[i]; c < list.start[i + 1]; ++c) {
            const std::size_t j = list.nbr[c];
            if (!geo(shape, i, j, rij, W, F)) continue;
            const Vec<D> a = (w * m[j] * F) * rij;
            self += a;
            if (j >= n) continue;
            for (std::size_t e = list.start[j] + j, e1 = list.start[j + 1] + j + 1; e < e1; ++e) {
              const double v = -a.dot(g_coef_[e]);
              if (v != 0.0) add(g_index_[e], v);
            }
          }
          for (std::size_t e = list.start[i] + i, e1 = list.start[i + 1] + i + 1; e < e1; ++e) {
            const double v = self.dot(g_coef_[e]);
            if (v != 0.0) add(g_index_[e], v);
          }
          rhs_[static_cast<Eigen::Index>(r)] = -w * rho[i] * divergence_[i] * inv_dt + (l_old - constant);
          finishRow(row_begin);
          continue;
        }
        // sum_j k_ij (p_i - p_j) [- zeta_i . grad p_i] = -rho_i div(v*)_i / dt,
        // k_ij = -8 rho_i m_j F_ij / (rho_i + rho_j)^2 > 0, zeta_i = sum_j k_ij r_ij (header).
        Vec<D> zeta = Vec<D>::Zero();
        double trace_m = 0;  // tr M_i = -sum_j V_j F_ij r_ij^2 (D on a full support)
        for (std::size_t c = list.start[i]; c < list.start[i + 1]; ++c) {
          const std::size_t j = list.nbr[c];
          if (!geo(shape, i, j, rij, W, F)) continue;
          const double s = rho[i] + rho[j];
          const double kij = -8.0 * rho[i] * m[j] * F / (s * s);
          add(i, kij);
          add(j, -kij);
          zeta += kij * rij;
          trace_m -= m[j] / rho[j] * F * rij.squaredNorm();
        }
        if (consistent) {
          // grad p_i = rho_i (G p)_i through the gradient row of i
          zeta *= -rho[i];
          const std::size_t e0 = list.start[i] + i, e1 = list.start[i + 1] + i + 1;
          for (std::size_t e = e0; e < e1; ++e) {
            const double v = zeta.dot(g_coef_[e]);
            if (v != 0.0) add(g_index_[e], v);
          }
        }
        // Consistent form: the operator scaled by D / tr M_i, so that it measures the second
        // derivatives with the weight of a full support also where the support is truncated
        // (near the free surface the plain sum is about half as large, and the projection
        // over-corrected there: an instability of the surface rows, docs/theory.md).
        const double scale = consistent && trace_m > 0 ? D / trace_m : 1.0;
        if (scale != 1.0)
          for (std::size_t q = row_begin; q < rb.vals.size(); ++q) rb.vals[q] *= scale;
        rhs_[static_cast<Eigen::Index>(r)] = -rho[i] * divergence_[i] * inv_dt + scale * (l_old - constant);
        finishRow(row_begin);
      }
    }
  });

  // Gather the rows (threads hold consecutive row ranges) into the compressed matrix.
  std::size_t nnz = 0;
  for (int t = 0; t < threads; ++t) nnz += rows_[static_cast<std::size_t>(t)].cols.size();
  SparseRowMatrix& matrix = out.matrix;
  matrix.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(rows));
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
void Projection<D>::correct(SphSystem<D>& sys, double dt, double* y, bool cleaning) {
  ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving;
  // The pressure (increment), or the cleaning multiplier (by unknown, 0 elsewhere).
  const double* p = cleaning ? multiplier_.data() : pressure_->data.data();
  const double* p_old = previous_pressure_.data();
  const bool incremental = incremental_ && !cleaning;
  double* yv = y + n * (D + 1);
  if (!cleaning) correction_.assign(n * D, 0.0);
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
  for (std::size_t k = 0; k < n; ++k) {
    Vec<D> a = Vec<D>::Zero();
    const std::size_t e0 = list.start[k] + k, e1 = list.start[k + 1] + k + 1;
    for (std::size_t e = e0; e < e1; ++e) {
      const Index q = g_index_[e];
      a += (incremental ? p[q] - p_old[q] : p[q]) * g_coef_[e];
    }
    for (int c = 0; c < D; ++c) {
      yv[D * k + c] -= dt * a[c];
      P.velocity[D * k + c] = yv[D * k + c];
      correction_[D * k + c] += a[c];
    }
  }
}

template <int D>
void Projection<D>::clean(SphSystem<D>& sys, double t, double dt, double* y) {
  // The exact projection of the corrected velocities (header): the source is their divergence
  // at the same positions (walls at rest), the gradient the adjoint of that divergence (thesis
  // eq. 3.18 without wall pressures), the multiplier is not a pressure and is not stored.
  gradientRows(sys, Gradient::symmetric, false);
  // Its own matrix and pattern record, so that the pressure solve keeps its symbolic analysis.
  assemble(sys, dt, Laplacian::exact, false, cleaning_system_);
  multiplier_.assign(sys.particles.size(), 0.0);
  cleaning_solution_.setZero(static_cast<Eigen::Index>(n_unknowns_));
  last_.cleaning = n_unknowns_ ? cleaning_solver_->solve(cleaning_system_.matrix, cleaning_system_.pattern_changed, rhs_, cleaning_solution_) : SolveReport{true, 0, 0.0, {}};
  if (!last_.cleaning.ok) {
    std::ostringstream os;
    os << "ISPH divergence cleaning failed at t = " << t << " s (" << n_unknowns_ << " unknowns): " << last_.cleaning.message;
    throw NumericalFailure(os.str());
  }
  for (std::size_t r = 0; r < n_unknowns_; ++r) multiplier_[particle_of_[r]] = cleaning_solution_[static_cast<Eigen::Index>(r)];
  correct(sys, dt, y, true);
}

template <int D>
void Projection<D>::correctPositions(SphSystem<D>& sys, double dt, double* y) {
  ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.n_moving;
  const double half_dt2 = 0.5 * dt * dt;
  // y starts with the positions (SphSystem::pack)
  for (std::size_t k = 0; k < n * D; ++k) {
    y[k] -= half_dt2 * correction_[k];
    P.position[k] = sys.domain.wrap(static_cast<int>(k % D), y[k]);
  }
}

template <int D>
void Projection<D>::storePressure(const SphSystem<D>& sys) {
  // Fluid: the solution on the unknowns, 0 on the free surface (and the pinned particle);
  // walls: the extrapolation p_w = sum_f c_wf p_f + b_w of the header.
  const std::size_t n = sys.particles.n_moving, N = sys.particles.size();
  double* p = pressure_->data.data();
  for (std::size_t i = 0; i < n; ++i) p[i] = 0.0;
  for (std::size_t r = 0; r < n_unknowns_; ++r) p[particle_of_[r]] = solution_[static_cast<Eigen::Index>(r)];
  const NeighbourList<D>& list = sys.neighbours;
  for (std::size_t w = n; w < N; ++w) {
    double pw = wall_offset_[w - n];
    for (std::size_t k = list.start[w]; k < list.split[w]; ++k) pw += wall_weight_[k] * p[list.nbr[k]];
    p[w] = pw;
  }
}

template <int D>
void Projection<D>::start(SphSystem<D>& sys, double t, double* y) {
  if (!incremental_) return;
  ParticleSet<D>& P = sys.particles;
  const std::size_t n = P.n_moving;
  // The pressure-free acceleration of the initial state (the pressure field is zero).
  std::vector<double> rate(sys.size());
  sys.evaluate(t, y, rate.data());
  const double* dvdt = rate.data() + n * (D + 1);
  // The projection of that acceleration, as a velocity over dt = 1, without the correction.
  for (std::size_t k = 0; k < n * D; ++k) P.velocity[k] = dvdt[k];
  flagFreeSurface(sys, t);
  numberUnknowns(sys);
  // As in the plain form (there is no previous pressure whose wall offsets would cancel the
  // hydrostatic ones); with no_penetration the "velocity" is the acceleration over dt = 1 here,
  // against which the gaps, in metres, are negligible.
  wallsAndSource(sys, 1.0, true, false);
  gradientRows(sys, gradient_, true);
  assemble(sys, 1.0, operator_(), incremental_, pressure_system_);
  solution_.setZero(static_cast<Eigen::Index>(n_unknowns_));
  const SolveReport rep = n_unknowns_ ? solver_->solve(pressure_system_.matrix, pressure_system_.pattern_changed, rhs_, solution_) : SolveReport{true, 0, 0.0, {}};
  if (!rep.ok) throw NumericalFailure("ISPH initial pressure solve failed: " + rep.message);
  storePressure(sys);
  sys.unpack(y);  // the velocities back
}

template <int D>
void Projection<D>::apply(SphSystem<D>& sys, double t, double dt, double* y) {
  const auto t0 = Clock::now();
  ParticleSet<D>& P = sys.particles;
  const std::size_t N = P.size();
  sys.unpack(y);
  if (sys.neighbours.update(P)) sys.driver.prepare(sys.neighbours);
  flagFreeSurface(sys, t);
  numberUnknowns(sys);
  gradientRows(sys, gradient_, true);
  // The divergence of v* with the walls at rest (reported, and the source of the incremental
  // form; wallsAndSource below computes the other forms' source).
  last_.divergence_before = divergence(sys, Vec<D>::Zero());
  if (predictor_) {
    // The carried pressure only predicted the stages' pressure force: take its share out of v*
    // (v** = v* + dt G p^n) and solve for the whole pressure below.
    const double* pn = pressure_->data.data();
    double* v = P.velocity.data();
    const std::size_t n = P.n_moving;
#pragma omp parallel for schedule(static) if (n >= kParallelMinimum)
    for (std::size_t k = 0; k < n; ++k) {
      Vec<D> a = Vec<D>::Zero();
      for (std::size_t e = sys.neighbours.start[k] + k, e1 = sys.neighbours.start[k + 1] + k + 1; e < e1; ++e)
        a += pn[g_index_[e]] * g_coef_[e];
      for (int c = 0; c < D; ++c) v[D * k + c] += dt * a[c];
    }
  }
  wallsAndSource(sys, dt, !incremental_ || predictor_, true);
  if (density_relaxation_time_ > 0) {
    // Density-invariant part of the source (Shao & Lo 2003; mixed with the divergence source as
    // Asai et al. 2012): the projected velocity's divergence is made (n_i/n_0 - 1)/tau instead
    // of zero, so that a particle packed closer than the lattice (n_i > n_0, the number
    // density at the positions the step reached) spreads and one spaced wider draws in, the
    // error relaxing over tau; a step longer than tau removes it at most once (fraction
    // min(1, dt/tau) per step). The rate is a time, not a fraction per step, so that the
    // correction's velocity does not grow as 1/dt under a tiny step (ARKODE's first). The
    // approximate projection alone keeps div v = 0 but lets the spacing drift
    // (docs/studies.md §5: the ISPH die packs 7-14 %).
    const double* nd = sys.particles.fields.find("number_density")->data.data();
    const double fraction = std::min(1.0, dt / density_relaxation_time_);
    const double rate = fraction / (lattice_number_density_ * dt), shift = fraction / dt;
    for (std::size_t i = 0; i < sys.particles.n_moving; ++i) divergence_[i] -= rate * nd[i] - shift;
  }
  assemble(sys, dt, operator_(), incremental_ && !predictor_, pressure_system_);
  // A closed domain (pinned pressure): the Neumann problem has a solution only when the
  // sources sum to zero; the discrete sources do not quite, and the pin would take the
  // remainder as a point source at one particle. Removing the mean spreads it evenly.
  if (pinned_ && n_unknowns_ > 0) rhs_.array() -= rhs_.mean();
  const auto t1 = Clock::now();

  // Warm start (iterative solver): the previous pressure.
  double* p = pressure_->data.data();
  solution_.resize(static_cast<Eigen::Index>(n_unknowns_));
  for (std::size_t r = 0; r < n_unknowns_; ++r) solution_[static_cast<Eigen::Index>(r)] = p[particle_of_[r]];
  last_.solve = n_unknowns_ ? solver_->solve(pressure_system_.matrix, pressure_system_.pattern_changed, rhs_, solution_) : SolveReport{true, 0, 0.0, {}};
  const auto t2 = Clock::now();
  if (!last_.solve.ok) {
    std::ostringstream os;
    os << "ISPH pressure solve failed at t = " << t << " s (" << n_unknowns_ << " unknowns): " << last_.solve.message;
    throw NumericalFailure(os.str());
  }

  if (incremental_) previous_pressure_.assign(p, p + N);
  storePressure(sys);
  correct(sys, dt, y, false);
  // The corrected velocities' divergence at the positions of the solve: what the projection
  // acts on (the position correction that follows moves the operator by O(dt^2)).
  last_.divergence_after = last_.divergence_projected = divergence(sys, Vec<D>::Zero());
  const auto t3 = Clock::now();
  if (cleaning_) clean(sys, t, dt, y);
  const auto t4 = Clock::now();
  if (cleaning_) last_.divergence_after = divergence(sys, Vec<D>::Zero());
  correctPositions(sys, dt, y);
  const auto t5 = Clock::now();

  last_.assembly_seconds = seconds(t0, t1);
  last_.cleaning_seconds = seconds(t3, t4);
  cleaning_seconds_ += last_.cleaning_seconds;
  last_.solve_seconds = seconds(t1, t2);
  assembly_seconds_ += last_.assembly_seconds;
  solve_seconds_ += last_.solve_seconds;
  correction_seconds_ += seconds(t2, t3) + seconds(t4, t5);
  if (cleaning_) {
    cleaning_iterations_total_ += static_cast<std::uint64_t>(last_.cleaning.iterations);
    cleaning_iterations_max_ = std::max(cleaning_iterations_max_, last_.cleaning.iterations);
    cleaning_residual_max_ = std::max(cleaning_residual_max_, last_.cleaning.residual);
  }
  ++solves_;
  iterations_total_ += static_cast<std::uint64_t>(last_.solve.iterations);
  iterations_max_ = std::max(iterations_max_, last_.solve.iterations);
  residual_max_ = std::max(residual_max_, last_.solve.residual);
  if (last_.divergence_before > 0)
    divergence_ratio_max_ = std::max(divergence_ratio_max_, last_.divergence_after / last_.divergence_before);
}

template <int D>
std::vector<std::string> Projection<D>::diagnosticsColumns() const {
  std::vector<std::string> c = {"solver_iterations", "solver_residual", "assembly_seconds", "solve_seconds",
                                "divergence_before", "divergence_after", "pressure_unknowns"};
  if (cleaning_) c.insert(c.end(), {"divergence_projected", "cleaning_iterations", "cleaning_residual", "cleaning_seconds"});
  return c;
}

template <int D>
void Projection<D>::diagnostics(std::vector<double>& v) const {
  v = {static_cast<double>(last_.solve.iterations), last_.solve.residual, last_.assembly_seconds, last_.solve_seconds,
       last_.divergence_before, last_.divergence_after, static_cast<double>(n_unknowns_)};
  if (cleaning_)
    v.insert(v.end(), {last_.divergence_projected, static_cast<double>(last_.cleaning.iterations), last_.cleaning.residual,
                       last_.cleaning_seconds});
}

template <int D>
void Projection<D>::saveCarried(NamedArrays& out) const {
  out.emplace_back("pressure", pressure_->data);
  out.emplace_back("totals", std::vector<double>{
      static_cast<double>(solves_), static_cast<double>(iterations_total_), static_cast<double>(iterations_max_),
      residual_max_, assembly_seconds_, solve_seconds_, correction_seconds_, divergence_ratio_max_,
      static_cast<double>(pressure_system_.pattern_builds), static_cast<double>(cleaning_iterations_total_),
      static_cast<double>(cleaning_iterations_max_), cleaning_residual_max_, cleaning_seconds_});
}

template <int D>
void Projection<D>::restoreCarried(const ArrayLookup& find) {
  const std::vector<double>* p = find("pressure");
  const std::vector<double>* t = find("totals");
  if (!p || !t || p->size() != pressure_->data.size() || t->size() != 13)
    throw InputError("--resume: the checkpoint lacks the ISPH pressure or solver totals (written by an older vesph?)");
  pressure_->data = *p;
  const auto count = [](double v) { return static_cast<std::uint64_t>(v); };
  solves_ = count((*t)[0]);
  iterations_total_ = count((*t)[1]);
  iterations_max_ = static_cast<int>((*t)[2]);
  residual_max_ = (*t)[3];
  assembly_seconds_ = (*t)[4];
  solve_seconds_ = (*t)[5];
  correction_seconds_ = (*t)[6];
  divergence_ratio_max_ = (*t)[7];
  pressure_system_.pattern_builds = count((*t)[8]);
  cleaning_iterations_total_ = count((*t)[9]);
  cleaning_iterations_max_ = static_cast<int>((*t)[10]);
  cleaning_residual_max_ = (*t)[11];
  cleaning_seconds_ = (*t)[12];
}

template <int D>
void Projection<D>::summarize(nlohmann::json& s) const {
  nlohmann::json j;
  j["linear_solver"] = solver_->name();
  j["solves"] = solves_;
  j["iterations_total"] = iterations_total_;
  j["iterations_max"] = iterations_max_;
  j["iterations_mean"] = solves_ ? static_cast<double>(iterations_total_) / static_cast<double>(solves_) : 0.0;
  j["max_relative_residual"] = residual_max_;
  j["assembly_seconds"] = assembly_seconds_;
  j["solve_seconds"] = solve_seconds_;
  j["correction_seconds"] = correction_seconds_;
  j["seconds_per_solve"] = solves_ ? solve_seconds_ / static_cast<double>(solves_) : 0.0;
  j["pattern_builds"] = pressure_system_.pattern_builds;
  j["max_divergence_ratio"] = divergence_ratio_max_;
  j["pressure_pinned"] = pinned_;
  j["divergence_cleaning"] = cleaning_;
  if (cleaning_) {
    j["cleaning_iterations_total"] = cleaning_iterations_total_;
    j["cleaning_iterations_max"] = cleaning_iterations_max_;
    j["cleaning_max_relative_residual"] = cleaning_residual_max_;
    j["cleaning_seconds"] = cleaning_seconds_;
  }
  s["isph"] = j;
}

template <int D>
std::string Projection<D>::describe() const {
  std::ostringstream os;
  const char* grad = gradient_ == Gradient::renormalised ? "renormalised difference form"
                     : gradient_ == Gradient::difference ? "difference form (thesis 3.17)"
                                                         : "symmetric form (thesis 3.18)";
  os << "# ISPH projection after every step: Laplacian " << (consistent_ ? "consistent (exact for linear fields)" : "thesis eq. (3.37) / Morris")
     << ", linear solver " << solver_->name() << ", pressure gradient " << grad << ";\n#   "
     << (has_free_surface_ ? "p = 0 on the particles [effects.free_surface] flags"
                           : "no free-surface detection: p = 0 at one pinned fluid particle (closed or periodic domain)")
     << ";\n#   " << (!incremental_ ? "plain form (no pressure carried in the right-hand side)"
                      : predictor_  ? "carried pressure as the stages' predictor, the whole pressure solved every step"
                                    : "incremental form (the pressure increment solved every step)")
     << "; walls " << (no_penetration_ ? "no_penetration (stop the approach closer than dx/2)" : "hydrostatic (Adami)") << "\n";
  if (velocity_inlet_)
    os << "#   inflow buffer as a velocity inlet: dp/dn = rho (u - u_w).e/dt there (inlet_condition = \"velocity\")\n";
  if (density_relaxation_time_ > 0)
    os << "#   density relaxation over " << density_relaxation_time_ << " s: the source targets div u = (n/n0 - 1)/tau (Shao & Lo 2003)\n";
  if (cleaning_)
    os << "#   then divergence cleaning: the exact projection onto discretely divergence-free velocities ("
       << cleaning_solver_->name() << ")\n";
  return os.str();
}

template <int D>
std::unique_ptr<StepHook<D>> makeProjection(ConfigTable& solver_table) {
  return std::make_unique<Projection<D>>(solver_table);
}

template class Projection<2>;
template class Projection<3>;
template std::unique_ptr<StepHook<2>> makeProjection<2>(ConfigTable&);
template std::unique_ptr<StepHook<3>> makeProjection<3>(ConfigTable&);

}  // namespace vesph
