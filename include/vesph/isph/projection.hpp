#pragma once
// Incompressible SPH: the projection of thesis §3.5 (Cummins & Rudman 1999) as a post-step
// hook (DESIGN.md "ISPH"). The right-hand side of an ISPH scene has no pressure: the
// integrator advances positions and velocities with the other forces (viscous, body, elastic)
// over a step dt to the intermediate velocity v*. After the accepted step this hook
//   1. flags the free surface at the accepted positions ([effects.free_surface], thesis §4.2);
//   2. solves for the pressure: p = 0 on free-surface particles (Dirichlet), and on the other
//      fluid particles the pressure Poisson equation of thesis §3.5,
//          div(grad p / rho) = div(v*) / dt,
//      with the divergence of the continuity equation (Fang eq. 26),
//          div(v)_i = -(1/rho_i) sum_j m_j (v_i - v_j) . grad_i W_ij,
//      and one of two Laplacians (solver.laplacian), both one kernel support wide:
//        morris      thesis eq. (3.37) in the variable-density form of Cummins & Rudman (1999),
//                        L p_i = sum_j k_ij (p_i - p_j),
//                        k_ij = -8 rho_i m_j F_ij / (rho_i + rho_j)^2,  F_ij = (dW/dr)/r,
//                    (L p ~ -lap p); it is exact for linear fields only where the kernel support
//                    is full: a truncated support (the particle rows within a support of the
//                    free surface) turns a linear pressure into a spurious source;
//        consistent  (default) the same with the first-order error removed (Schwaiger 2008;
//                    Fatehi & Manzari 2011):
//                        L p_i = sum_j k_ij (p_i - p_j - r_ij . grad p_i),
//                    grad p_i the renormalised gradient below: exact for linear fields on any
//                    support, so a hydrostatic pressure is reproduced up to the free surface.
//      The equation solved is L p_i = -rho_i div(v*)_i / dt. The projection is approximate
//      (Cummins & Rudman): L is not the composition of the discrete divergence and gradient, so
//      the divergence of the corrected velocity is reduced to the operators' truncation error,
//      not to the solver tolerance. (The exact composition div_h G reaches two supports and
//      annihilates pressure modes at the lattice scale: as the pressure equation it is
//      near-singular, and its solutions grew without bound in the hydrostatic tank; it serves
//      the divergence cleaning of step 4 instead; docs/theory.md.) Wall particles enter the
//      source divergence with u_w + dt g: the wall pressure's hydrostatic part answers the body
//      force's share of v*.n, which is not counted twice (a fluid at rest under gravity gets a
//      zero source and exactly the hydrostatic pressure).
//      The walls' pressure is extrapolated from the fluid as in WCSPH (Adami et al. 2012,
//      eq. 27: p_w = sum_f p_f W_wf / sum_f W_wf + rho0 g . sum_f (r_w - r_f) W_wf / sum_f W_wf)
//      and eliminated into the fluid rows: the discrete Neumann condition grad p . n = rho g . n;
//      with solver.wall_condition = "no_penetration" (plain and predictor forms) instead
//          p_w = sum_f c_wf p_f + rho0 sum_f c_wf min(delta_f, 0) (n_f . r_wf) / dt,
//          delta_f = (u_f - u_w) . n_f + gap_f / dt,
//      u the velocity the projection corrects (v* or v**, below), n_f = -sum_w V_w grad W_fw/|.|
//      the unit normal away from the walls in f's support, gap_f = max(0, min_w n_f . r_fw - dx)
//      how far f may still approach before it reaches the lattice's rest distance (dx/2 above
//      the wall surface): the discrete form of grad p . n = rho (u - u_w) . n / dt, applied only
//      where f would otherwise come closer than that within dt (the walls push, never pull);
//      the normal flux into the walls then leaves the source divergence (it is these Neumann
//      data, not a volume source). A fluid at rest under gravity gets u . n = dt g . n and the
//      hydrostatic wall pressure as before.
//      A prescribed inflow buffer (kind inflow) is such a wall (hydrostatic data: zero gradient
//      without gravity); with solver.inlet_condition = "velocity" (plain and predictor
//      forms) its particles take
//          p_w = sum_f c_wf p_f + rho0 sum_f c_wf ((u_f - u_w) . e)(e . r_wf) / dt,
//      e the flow direction: grad p . e = rho (u - u_w) . e / dt, push and pull, so that the
//      correction brings the rows next to the buffer to its speed, plus the walls' hydrostatic
//      term across the flow, rho0 (g - (g.e) e) . r_wf; the flux along e through the buffer then
//      leaves the source divergence (docs/theory.md §10, the velocity inlet).
//      Incremental form (Goda 1979; van Kan 1986), when the scene lists
//      [effects.pressure_gradient]: the right-hand side then carries the last projection's
//      pressure p^n through the step (best with form = "renormalised", the gradient below), so
//      that the integrator's stages see the pressure force; the projection solves
//          L p^{n+1} = L p^n - rho_i div(v*)_i / dt
//      (the same operator, the same Dirichlet and wall conditions; the walls enter the source
//      at rest, since the hydrostatic wall offsets of p^{n+1} and p^n cancel) and corrects with
//      p^{n+1} - p^n in step 3. A fluid in equilibrium then stays exactly in equilibrium: without
//      it, the stages see v* = v + t g without the pressure that balances g, and the viscous
//      term of a no-slip wall acts on that spurious motion (a splitting error of O(nu dt / h^2)).
//      solver.carried_pressure = "predictor" keeps the carried pressure in the right-hand side
//      but solves each projection for the whole pressure: with v** = v* + dt G p^n (the stages'
//      pressure force taken out again, G at the step's end positions),
//          L p^{n+1} = -rho_i div(v**)_i / dt,   v^{n+1} = v** - dt G p^{n+1}
//      (the plain form's equation and walls; the correction is the same G (p^{n+1} - p^n) on v*).
//      Were L = rho div_h G the two would agree; for the approximate projection the increment
//      form keeps, step after step, whatever part of p^n the mismatch L - rho div_h G leaves
//      unanswered (pressure modes that G hardly moves) and the predictor form forgets it
//      (docs/theory.md §10 has what each does in the tank, a block impact and the drops).
//      The incremental form starts from the pressure that makes the initial acceleration
//      divergence-free (the same equation with v* the initial pressure-free acceleration and
//      dt = 1): a fluid that starts at rest under gravity starts with its hydrostatic pressure.
//      solver.density_relaxation_time = tau (Shao & Lo 2003, mixed as Asai et al. 2012)
//      subtracts f (n_i/n_0 - 1)/dt, f = min(1, dt/tau), from div(v*)_i (any form): the
//      corrected velocity's divergence is that target instead of zero, which spreads particles
//      packed closer than the lattice (n_i, the free-surface effect's number density; n_0 the
//      lattice's) over the time tau.
//   3. corrects velocities and positions of all fluid particles,
//          v_i = v*_i - dt (G p)_i,  x_i = x_i - dt^2/2 (G p)_i   (incremental: G (p^{n+1} - p^n)),
//      with G (solver.gradient) the renormalised difference form (default; Randles & Libersky
//      1996, exact for linear pressure fields, also at the free surface and the walls),
//          (G p)_i = (1/rho_i) M_i^-1 sum_j V_j (p_j - p_i) grad_i W_ij,
//          M_i = -sum_j V_j F_ij r_ij r_ij^T,  V_j = m_j/rho_j
//      (M_i = I where it is near-singular: smallest eigenvalue below 0.1, an isolated particle),
//      or thesis eq. (3.17) (difference, M = I) or (3.18) (symmetric, momentum-conserving).
//      The position correction is the pressure acceleration's share of the step taken as
//      constant over it: a second-order integrator moved the particles by dt (v^n + v*)/2, so
//      the corrected positions are the thesis' x^{n+1} = x^n + dt (v^n + v^{n+1})/2.
//   4. (solver.divergence_cleaning) the exact projection of the corrected velocities u onto
//      the discretely divergence-free fields: with D the continuity divergence above, restricted
//      to the unknowns and linear in the fluid velocities (walls keep theirs),
//          u <- u - dt G_a phi,   V_i (D G_a phi)_i = V_i (D u)_i / dt,
//          (G_a phi)_k = sum_j m_j (phi_k / rho_k^2 + phi_j / rho_j^2) grad_k W_kj,
//      phi = 0 on free-surface and wall particles. G_a = -M^-1 D^T V (M = diag m, V = diag m/rho)
//      is the adjoint of D, so V D G_a is symmetric negative semi-definite: the kinetic-energy
//      orthogonal projection, which only removes energy. Its null space (checkerboards) does
//      not move u; a relative diagonal shift of 1e-10 makes the matrix definite for UMFPACK/KLU.
//      phi is a multiplier, not a pressure: the stored pressure stays that of step 2.
//      Positions are corrected with the same -dt^2/2 G_a phi.
// Without free-surface detection (closed or periodic domains) the pressure is fixed by
// p = 0 at one fluid particle (the first), which makes the Neumann problem non-singular; the
// mean of the right-hand side is removed first (solvability of the Neumann problem).
// The matrix is assembled from the pairs inside the kernel support; when its pattern equals
// the previous step's (no pair crossed the support, the free surface kept its particles), the
// direct solvers keep their symbolic analysis.
#include <chrono>
#include <memory>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/isph/linear_solver.hpp"
#include "vesph/physics/step_hook.hpp"

namespace vesph {

template <int D>
class Projection final : public StepHook<D> {
 public:
  explicit Projection(ConfigTable& solver_table);

  std::string_view name() const override { return "isph_projection"; }
  void setup(Setup<D>& s) override;
  bool changesState() const override { return true; }
  void start(StepContext<D>& system, double t, double* y) override;
  void apply(StepContext<D>& system, double t, double dt, double* y) override;
  // The incremental form keeps the last pressure per particle: it follows the particles when
  // an inflow or outflow changes the set (a released particle starts from its buffer
  // particle's pressure).
  void resized(StepContext<D>& system, const ParticleRemap& remap) override {
    if (previous_pressure_.size() == remap.old_size) remap.apply(previous_pressure_, 1, Field::Range::all);
  }
  // Checkpoints keep the pressure field (the incremental form's p^n, the iterative solvers'
  // first guess) and the run's solver totals; on resume they replace what start() computed.
  void saveCarried(NamedArrays& out) const override;
  void restoreCarried(const ArrayLookup& find) override;
  std::vector<std::string> diagnosticsColumns() const override;
  void diagnostics(std::vector<double>& values) const override;
  void summarize(nlohmann::json& summary) const override;
  std::string describe() const override;

  // Root-mean-square of the discrete divergence (1/s) over the pressure unknowns, before and
  // after the last projection (the "after" value at the corrected positions).
  double divergenceBefore() const { return last_.divergence_before; }
  double divergenceAfter() const { return last_.divergence_after; }
  // With divergence cleaning: after the pressure projection, before the cleaning.
  double divergenceProjected() const { return last_.divergence_projected; }
  const SolveReport& lastCleaning() const { return last_.cleaning; }
  const SolveReport& lastSolve() const { return last_.solve; }
  std::size_t unknowns() const { return n_unknowns_; }

 private:
  struct LastProjection {
    SolveReport solve, cleaning;
    double assembly_seconds = 0, solve_seconds = 0, divergence_before = 0, divergence_after = 0;
    double divergence_projected = 0, cleaning_seconds = 0;
  };
  void flagFreeSurface(StepContext<D>& sys, double t);
  void numberUnknowns(const StepContext<D>& sys);
  // inlet_data (wallExtrapolation, wallsAndSource, divergence): the inflow buffer as a velocity
  // inlet (solver.inlet_condition = "velocity") in this solve.
  void wallExtrapolation(const StepContext<D>& sys, double dt, bool inlet_data);
  void wallNormals(StepContext<D>& sys);
  void wallsAndSource(StepContext<D>& sys, double dt, bool whole_pressure, bool inlet_data);
  // One assembled matrix with the record of its sparsity pattern (the direct solvers keep their
  // symbolic analysis while it holds): the pressure equation's, and the cleaning's.
  struct Assembled {
    SparseRowMatrix matrix;
    std::vector<int> outer, inner;  // the pattern of the previous assembly
    std::size_t pattern_builds = 0;
    bool pattern_changed = true;
  };
  enum class Gradient { renormalised, difference, symmetric };
  enum class Laplacian { consistent, morris, exact };
  void gradientRows(StepContext<D>& sys, Gradient form, bool walls_enter);
  void assemble(StepContext<D>& sys, double dt, Laplacian op, bool incremental, Assembled& out);
  Laplacian operator_() const { return consistent_ ? Laplacian::consistent : Laplacian::morris; }
  void clean(StepContext<D>& sys, double t, double dt, double* y);
  double divergence(StepContext<D>& sys, const Vec<D>& wall_shift, bool tangential_walls = false,
                    bool inlet_data = false);
  void correct(StepContext<D>& sys, double dt, double* y, bool cleaning);
  void correctPositions(StepContext<D>& sys, double dt, double* y);
  void storePressure(const StepContext<D>& sys);

  LinearSolverOptions options_;
  Gradient gradient_ = Gradient::renormalised;
  bool consistent_ = true, incremental_ = false, cleaning_ = false;
  // solver.wall_condition = "no_penetration": the walls' Neumann data carry the fluid's normal
  // velocity (header, step 2) instead of the hydrostatic balance alone; solver.carried_pressure
  // = "predictor": the whole pressure solved every step (header, incremental form).
  bool no_penetration_ = false, predictor_ = false;
  // solver.inlet_condition = "velocity": the inflow buffer's pressure carries the Neumann data
  // of its velocity (inflow_direction_ = e, the flow direction, taken from the inflow hook at
  // the first step's solve).
  bool velocity_inlet_ = false;
  Vec<D> inflow_direction_ = Vec<D>::Zero();
  std::vector<Vec<D>> wall_normal_;     // per moving particle: unit normal away from the walls (0: none near)
  std::vector<double> wall_gap_;        // per moving particle: the approach left before the rest distance, m
  LinearSolverOptions cleaning_options_;
  std::unique_ptr<LinearSolver> cleaning_solver_;
  std::vector<double> multiplier_;
  Eigen::VectorXd cleaning_solution_;
  std::uint64_t cleaning_iterations_total_ = 0;
  int cleaning_iterations_max_ = 0;
  double cleaning_residual_max_ = 0, cleaning_seconds_ = 0;
  std::vector<double> previous_pressure_;
  std::unique_ptr<LinearSolver> solver_;
  Effect<D>* free_surface_effect_ = nullptr;
  const Field* surface_flag_ = nullptr;
  Field* pressure_ = nullptr;
  Vec<D> g_ = Vec<D>::Zero();
  double rho0_ = 1;
  // solver.density_relaxation_time (tau, s; 0: off) and the lattice's number density, 1/m^D,
  // against which the free-surface effect's number density at the step's positions is compared.
  double density_relaxation_time_ = 0, lattice_number_density_ = 1;
  bool pinned_ = false, has_free_surface_ = false;

  // Unknowns: the fluid particles off the free surface (unknown_of_[i] = row or -1).
  std::vector<int> unknown_of_, particle_of_;
  std::size_t n_unknowns_ = 0;
  // Wall extrapolation weights c_wf = W_wf / sum W, by neighbour-list entry of the wall
  // particle's moving candidates, and its constant part b_w (hydrostatic), by fixed index.
  std::vector<double> wall_weight_, wall_offset_;
  // The pressure acceleration G p of each moving particle k as a linear combination of the
  // pressures of k and its candidates: entries [start[k] + k, start[k+1] + k + 1) of the
  // neighbour-list layout, the first for k itself (coefficient 0 beyond the support).
  std::vector<Index> g_index_;
  std::vector<Vec<D>> g_coef_;
  // The system, row by row (per thread while assembling), and pattern bookkeeping.
  struct RowBuffer {
    std::vector<int> slot;       // column -> position in cols (or -1)
    std::vector<int> cols, lengths;
    std::vector<double> vals;
  };
  std::vector<RowBuffer> rows_;
  Assembled pressure_system_, cleaning_system_;
  Eigen::VectorXd rhs_, solution_;
  std::vector<double> divergence_;  // per moving particle: div v*
  std::vector<double> correction_;  // per moving particle: the velocity correction / dt

  LastProjection last_;
  std::uint64_t solves_ = 0, iterations_total_ = 0;
  int iterations_max_ = 0;
  double residual_max_ = 0, assembly_seconds_ = 0, solve_seconds_ = 0, correction_seconds_ = 0;
  double divergence_ratio_max_ = 0;
};

template <int D>
std::unique_ptr<StepHook<D>> makeProjection(ConfigTable& solver_table);

}  // namespace vesph
