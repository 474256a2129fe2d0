// The walls of the ISPH pressure equation (docs/theory.md §10; docs/architecture.md
// "ISPH projection"): their extrapolated pressure and the source divergence.
//
// Wall particles enter the source divergence with u_w + dt g: the wall pressure's hydrostatic
// part answers the body force's share of v*.n, which is not counted twice (a fluid at rest
// under gravity gets a zero source and exactly the hydrostatic pressure).
// The walls' pressure is extrapolated from the fluid as in WCSPH (Adami et al. 2012, eq. 27:
//     p_w = sum_f p_f W_wf / sum_f W_wf + rho0 g . sum_f (r_w - r_f) W_wf / sum_f W_wf)
// and eliminated into the fluid rows: the discrete Neumann condition grad p . n = rho g . n
// (solver.wall_condition = "hydrostatic"); with solver.wall_condition = "no_penetration"
// (plain and predictor forms) instead
//     p_w = sum_f c_wf p_f + rho0 sum_f c_wf min(delta_f, 0) (n_f . r_wf) / dt,
//     delta_f = (u_f - u_w) . n_f + gap_f / dt,
// u the velocity the projection corrects (v* or v**, include/vesph/isph/projection.hpp),
// n_f = -sum_w V_w grad W_fw/|.| the unit normal away from the walls in f's support,
// gap_f = max(0, min_w n_f . r_fw - dx) how far f may still approach before it reaches the
// lattice's rest distance (dx/2 above the wall surface): the discrete form of
// grad p . n = rho (u - u_w) . n / dt, applied only where f would otherwise come closer than
// that within dt (the walls push, never pull); the normal flux into the walls then leaves the
// source divergence (it is these Neumann data, not a volume source). A fluid at rest under
// gravity gets u . n = dt g . n and the hydrostatic wall pressure as before.
// A prescribed inflow buffer (kind inflow) is such a wall (hydrostatic data: zero gradient
// without gravity); with solver.inlet_condition = "velocity" (plain and predictor forms) its
// particles take
//     p_w = sum_f c_wf p_f + rho0 sum_f c_wf ((u_f - u_w) . e)(e . r_wf) / dt,
// e the flow direction: grad p . e = rho (u - u_w) . e / dt, push and pull, so that the
// correction brings the rows next to the buffer to its speed, plus the walls' hydrostatic term
// across the flow, rho0 (g - (g.e) e) . r_wf; the flux along e through the buffer then leaves
// the source divergence (docs/theory.md §10, the velocity inlet).
// Moving walls (vesph/boundary/moving_walls.hpp): u_w is the wall particle's prescribed velocity
// (in the source divergence and the no-penetration data), and the hydrostatic offset takes
// rho0 (g - a_w), a_w the wall's acceleration (Adami eq. 27).
// Solving for the increment of the carried pressure, the hydrostatic wall offsets of p^{n+1}
// and p^n cancel and the walls enter the source at rest.
#include <algorithm>
#include <cmath>
#include <limits>

#include "projection_parts.hpp"
#include "vesph/core/pair_loop.hpp"

namespace vesph::isph {

template <int D>
void WallConditions<D>::prepare(StepContext<D>& sys, double dt, SolvedFor solved_for, const VelocityInlet<D>* inlet,
                                std::vector<double>& divergence) {
  // The walls' Neumann data and the source divergence of the velocity in P.velocity. Solving
  // for the whole pressure (plain and predictor forms, the initial pressure), the hydrostatic
  // wall offsets answer the body force's share dt g of that velocity, so the walls enter the
  // source moving with u_w + dt g; solving for the increment, the walls enter at rest
  // (`divergence` then holds the divergence the projection computed for the report).
  // no_penetration: the normal velocity is in the wall offsets and the walls' normal flux
  // leaves the source.
  if (condition_ == WallCondition::no_penetration) computeNormals(sys);
  extrapolate(sys, dt, inlet);
  if (condition_ == WallCondition::no_penetration)
    continuityDivergence(sys, WallFlux<D>{Vec<D>::Zero(), &normal_, inlet}, divergence);
  else if (solved_for == SolvedFor::pressure)
    continuityDivergence(sys, WallFlux<D>{Vec<D>(dt * g_), nullptr, inlet}, divergence);
}

template <int D>
void WallConditions<D>::computeNormals(StepContext<D>& sys) {
  // n_i = -sum_w V_w grad_i W_iw / |.|: away from the wall particles in i's support (for a
  // particle over a flat wall the wall's normal, also at the edge of a spreading film, where the
  // wall extends on both sides of it; at a corner the bisector). Zero without wall neighbours.
  // gap_i: how far i may still approach the walls before it reaches the rest distance of the
  // lattice (half a spacing above the wall surface, i.e. one spacing from the first wall row).
  const ParticleSet<D>& P = sys.particles;
  normal_.assign(P.n_moving, Vec<D>::Zero());
  gap_.assign(P.n_moving, 0.0);
  const double* m = P.mass.data();
  const double* rho = P.density.data();
  sys.driver.forEachMoving(P, sys.kernel, sys.domain, sys.neighbours, false,
                           [&](Index i, std::span<const Neighbour<D>>, std::span<const Neighbour<D>> fixed) {
                             Vec<D> s = Vec<D>::Zero();
                             for (const Neighbour<D>& nb : fixed) s -= (m[nb.j] / rho[nb.j] * nb.F) * nb.rij;
                             const double norm = s.norm();
                             if (norm == 0) return;
                             const Vec<D> n = s / norm;
                             normal_[i] = n;
                             double nearest = std::numeric_limits<double>::infinity();
                             for (const Neighbour<D>& nb : fixed) nearest = std::min(nearest, n.dot(nb.rij));
                             const double spacing = std::pow(m[i] / rho[i], 1.0 / D);
                             gap_[i] = std::max(0.0, nearest - spacing);
                           });
  // The walls' extrapolation reads them at the ghosts too (their fluid neighbours).
  if (distribution_) {
    static_assert(sizeof(Vec<D>) == D * sizeof(double), "normals are packed as D doubles each");
    const HaloArray arrays[2] = {{normal_.data()->data(), D, Field::Range::moving}, {gap_.data(), 1, Field::Range::moving}};
    distribution_->refreshArrays(arrays);
  }
}

template <int D>
void WallConditions<D>::extrapolate(const StepContext<D>& sys, double dt, const VelocityInlet<D>* inlet) {
  const ParticleSet<D>& P = sys.particles;
  const NeighbourList<D>& list = sys.neighbours;
  const std::size_t n = P.n_moving, N = P.size();
  weight_.resize(list.nbr.size());
  offset_.assign(N - n, 0.0);
  const CandidatePairs<D> pairs(P, sys.kernel, sys.domain, list);
  const Vec<D> rho_g = rho0_ * g_;
  const bool no_penetration = condition_ == WallCondition::no_penetration;
  // The inlet: across the flow the buffer is a hydrostatic wall (the source shifts it by dt g
  // like the walls); along e the body force's share dt g.e is in u_f already.
  const Vec<D> e = inlet ? inlet->direction : Vec<D>::Zero();
  const Vec<D> rho_g_across = rho_g - rho_g.dot(e) * e;
  const double* v = P.velocity.data();
  const double rho0 = rho0_;
  // Moving walls (vesph/boundary/moving_walls.hpp): rho0 (g - a_w) in the hydrostatic offset.
  const Field* wall_acceleration = P.fields.find("wall_acceleration");
  sys.kernel.visit([&](auto shape) {
#pragma omp parallel for schedule(static) if (N - n >= kParallelMinimum)
    for (std::size_t w = n; w < N; ++w) {
      Vec<D> rho_g_w = rho_g;
      if (wall_acceleration)
        for (int a = 0; a < D; ++a) rho_g_w[a] -= rho0 * wall_acceleration->data[D * (w - n) + a];
      double sumW = 0, offset = 0, push = 0;  // offset: hydrostatic; push: no_penetration
      double inflow = 0;                      // the velocity inlet: the buffer's Neumann data
      const bool buffer = inlet && P.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow);
      pairs.visit(
          shape, w, list.start[w], list.split[w],
          [&](std::size_t k, std::size_t f, const Vec<D>& rij, double W, double) {
            weight_[k] = W;
            sumW += W;
            if (buffer) {
              // The fluid's velocity along the flow relative to the buffer's: the pressure step
              // rho0 (u_f - u_w).e (e . r_wf) / dt over f's makes -dt G p bring the rows next to
              // the buffer to its speed (above).
              double ue = 0;
              for (int a = 0; a < D; ++a) ue += (v[D * f + a] - v[D * w + a]) * e[a];
              inflow += rho0 * ue * e.dot(rij) * W;
              offset += rho_g_across.dot(rij) * W;
              return;
            }
            if (!no_penetration) {
              offset += rho_g_w.dot(rij) * W;  // rij = r_w - r_f
            } else {
              // The normal velocity of f relative to the wall beyond what closes its gap within
              // dt: delta < 0 is an approach the correction must stop, and the wall pressure
              // rho0 delta (n_f . r_wf) / dt above f's does (above). Only a push: the walls do
              // not hold the fluid back where it moves away.
              const Vec<D>& nf = normal_[f];
              double un = 0;
              for (int a = 0; a < D; ++a) un += (v[D * f + a] - v[D * w + a]) * nf[a];
              const double delta = un + gap_[f] / dt;
              push += rho0 * std::min(delta, 0.0) * nf.dot(rij) * W;
            }
          },
          [&](std::size_t k) { weight_[k] = 0.0; });
      const double inv = sumW > 0 ? 1.0 / sumW : 0.0;
      for (std::size_t k = list.start[w]; k < list.split[w]; ++k) weight_[k] *= inv;
      // hydrostatic: Adami et al. eq. 27. no_penetration: the push alone: the velocity it
      // answers (v* of the plain form, v** of the predictor form) carries dt g, so the
      // hydrostatic part is in it.
      offset_[w - n] = buffer ? (inflow / dt + offset) * inv : no_penetration ? push * inv / dt : offset * inv;
    }
  });
}

template class WallConditions<2>;
template class WallConditions<3>;

}  // namespace vesph::isph
