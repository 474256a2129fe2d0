#pragma once
// The pieces of the ISPH projection (include/vesph/isph/projection.hpp; docs/architecture.md
// "ISPH projection"), private to src/isph: the operators the projection composes, which
// carry out the strategies it chose from [solver] (the enums of projection.hpp).
//   PressureUnknowns     which fluid particles carry an unknown (src/isph/pressure_system.cpp)
//   GradientRows         the pressure gradient G as rows over the neighbour list (same file)
//   PressureSystem       the assembled pressure equation (same file)
//   WallConditions       the walls' (and the inflow buffer's) extrapolated pressure and the
//                        source divergence (src/isph/wall_conditions.cpp)
//   DivergenceCleaning   the optional exact projection after the pressure correction
//                        (src/isph/divergence_cleaning.cpp)
// They take the hook's `sys` and read only its particles, kernel, domain, neighbours and driver
// (the projection itself adds unpack, evaluate and size).
#include <memory>
#include <optional>
#include <vector>

#include "vesph/isph/linear_solver.hpp"
#include "vesph/isph/projection.hpp"
#include "vesph/physics/step_hook.hpp"

namespace vesph::isph {

// Whether the wall particles' pressures enter the gradient rows (the cleaning's gradient is
// the adjoint of the divergence over the fluid, without them).
enum class WallPressures { enter, excluded };
// What one solve is for: the whole pressure (the plain and predictor forms, the initial
// pressure), or the increment over the carried pressure (the incremental form's steps).
enum class SolvedFor { pressure, increment };

// Unknowns: the fluid particles off the free surface (unknown_of[i] = column or -1). In a run
// across processes the rows are this process's owned fluid particles, [0, count), and the
// columns go on with its ghosts' unknowns, [count, columns): `across` numbers them globally (the
// owners' numbers, refreshed into the ghosts); serially columns = count.
struct PressureUnknowns {
  std::vector<int> unknown_of, particle_of;
  std::size_t count = 0, columns = 0;
  std::uint64_t global_count = 0;  // every process's rows
  // No Dirichlet particle this step (closed or periodic domain): p = 0 at the fluid particle
  // with the smallest id fixes the pure Neumann problem's constant.
  bool pinned = false;
  DistributedRows across;  // with a distribution only

  // surface_flag: 1 on the free surface (nullptr: no detection); distribution: null serially.
  // Collective with a distribution.
  template <int D>
  void number(const ParticleSet<D>& particles, const double* surface_flag, ParticleDistribution<D>* distribution);
  // Root-mean-square over every process's unknowns of a per-moving-particle value.
  template <int D>
  double rms(const std::vector<double>& per_particle, ParticleDistribution<D>* distribution) const;

 private:
  std::vector<double> global_number_;  // per moving particle, for the halo refresh
};

// How the wall neighbours' velocities enter the continuity divergence.
template <int D>
struct WallFlux {
  Vec<D> shift = Vec<D>::Zero();  // the walls move with u_w + shift
  // no_penetration: the fluid particles' wall normals; the normal flux into the walls is then
  // the walls' Neumann data, not a source.
  const std::vector<Vec<D>>* normal_flux_removed = nullptr;
  // The velocity inlet: the flux along e through the buffer is the buffer's Neumann data.
  const VelocityInlet<D>* inlet = nullptr;
};

// The continuity divergence (Fang eq. 26) of P.velocity at every moving particle into `out`:
//   div(v)_i = -(1/rho_i) sum_j m_j (v_i - v_j) . grad_i W_ij.
template <int D>
void continuityDivergence(StepContext<D>& sys, const WallFlux<D>& walls, std::vector<double>& out);

// The pressure acceleration G p of each moving particle k as a linear combination of the
// pressures of k and its candidates: entries [start[k] + k, start[k+1] + k + 1) of the
// neighbour-list layout, the first for k itself (coefficient 0 beyond the support).
template <int D>
struct GradientRows {
  std::vector<Index> index;
  std::vector<Vec<D>> coef;

  void build(StepContext<D>& sys, GradientForm form, WallPressures walls);

 private:
  // One pair inside the support, kept between the two passes of build() (the renormalisation
  // matrix, then the coefficients) so that the kernel is evaluated once per pair.
  struct PairGeometry {
    std::size_t entry, j;
    Vec<D> rkj;
    double F;
  };
  std::vector<std::vector<PairGeometry>> pairs_;  // per thread, reused from step to step

 public:
  // (G p)_k; with p_old, (G (p - p_old))_k.
  Vec<D> at(const NeighbourList<D>& list, std::size_t k, const double* p, const double* p_old = nullptr) const {
    Vec<D> a = Vec<D>::Zero();
    const std::size_t e0 = list.start[k] + k, e1 = list.start[k + 1] + k + 1;
    if (p_old) {
      for (std::size_t e = e0; e < e1; ++e) a += (p[index[e]] - p_old[index[e]]) * coef[e];
    } else {
      for (std::size_t e = e0; e < e1; ++e) a += p[index[e]] * coef[e];
    }
    return a;
  }
};

// The walls' pressure p_w = sum_f c_wf p_f + b_w, eliminated into the fluid rows, with the
// wall condition chosen at setup (solver.wall_condition) and the optional velocity inlet
// (wall_conditions.cpp has the equations).
template <int D>
class WallConditions {
 public:
  WallConditions(WallCondition condition, std::optional<VelocityInlet<D>> inlet, double rest_density,
                 const Vec<D>& body_acceleration)
      : condition_(condition), inlet_(inlet), rho0_(rest_density), g_(body_acceleration) {}

  WallCondition condition() const { return condition_; }
  // A run across processes: the ghosts' wall normals and gaps come from their owners.
  void setDistribution(ParticleDistribution<D>* distribution) { distribution_ = distribution; }
  const VelocityInlet<D>* inlet() const { return inlet_ ? &*inlet_ : nullptr; }

  // The wall data for a solve over dt of the velocity in P.velocity, and the source
  // divergence into `divergence` (left as it is where the walls enter at rest: hydrostatic
  // walls, solving for the increment). inlet: the velocity inlet's data in this solve (nullptr
  // at the initial solve, whose P.velocity holds an acceleration).
  void prepare(StepContext<D>& sys, double dt, SolvedFor solved_for, const VelocityInlet<D>* inlet,
               std::vector<double>& divergence);

  // Extrapolation weights c_wf = W_wf / sum W, by neighbour-list entry of the wall particle's
  // moving candidates, and the constant part b_w, by fixed index.
  const std::vector<double>& weights() const { return weight_; }
  const std::vector<double>& offsets() const { return offset_; }

 private:
  void computeNormals(StepContext<D>& sys);
  void extrapolate(const StepContext<D>& sys, double dt, const VelocityInlet<D>* inlet);

  WallCondition condition_;
  std::optional<VelocityInlet<D>> inlet_;
  double rho0_;
  Vec<D> g_;
  std::vector<double> weight_, offset_;
  std::vector<Vec<D>> normal_;  // per moving particle: unit normal away from the walls (0: none near)
  std::vector<double> gap_;     // per moving particle: the approach left before the rest distance, m
  ParticleDistribution<D>* distribution_ = nullptr;
};

// One assembled matrix with the record of its sparsity pattern (the direct solvers keep their
// symbolic analysis while it holds): the pressure equation's, and the cleaning's.
struct AssembledMatrix {
  SparseRowMatrix matrix;
  std::vector<int> outer, inner;  // the pattern of the previous assembly
  std::size_t pattern_builds = 0;
  bool pattern_changed = true;
};

// The assembly of L p = -rho div / dt over the unknowns (pressure_system.cpp).
template <int D>
class PressureSystem {
 public:
  explicit PressureSystem(double rest_density) : rho0_(rest_density) {}
  // The rows of `form` into out.matrix and rhs(): divergence per moving particle; carried:
  // the last pressure whose operator goes to the right-hand side (the incremental form's
  // L p^n), or nullptr. known: the pressures of the fluid particles that are not unknowns (the
  // free surface's Dirichlet values, solver.surface_pressure), moved to the right-hand side;
  // nullptr: p = 0 there.
  void assemble(StepContext<D>& sys, double dt, LaplacianForm form, const PressureUnknowns& unknowns,
                const GradientRows<D>& gradient, const WallConditions<D>& walls, const std::vector<double>& divergence,
                const double* carried, AssembledMatrix& out, const double* known = nullptr);
  Eigen::VectorXd& rhs() { return rhs_; }

 private:
  // The system, row by row (per thread while assembling).
  struct RowBuffer {
    std::vector<int> slot;  // column -> position in cols (or -1)
    std::vector<int> cols, lengths;
    std::vector<double> vals;
    std::vector<double> row_vals;  // one row's values while its columns are sorted
  };
  std::vector<RowBuffer> rows_;
  Eigen::VectorXd rhs_;
  double rho0_;
};

// What the projection's stages share: the hook passes it to the optional cleaning stage.
template <int D>
struct ProjectionOperators {
  PressureUnknowns& unknowns;
  GradientRows<D>& gradient;
  PressureSystem<D>& system;
  const WallConditions<D>& walls;
  std::vector<double>& divergence;  // per moving particle
  std::vector<double>& correction;  // per moving particle: the velocity correction / dt
};

// v <- v - dt G p (G (p - p_old) with p_old) on the moving particles, in y and P.velocity;
// the correction G p is added to ops.correction.
template <int D>
void correctVelocities(StepContext<D>& sys, const ProjectionOperators<D>& ops, double dt, double* y, const double* p,
                       const double* p_old);

// Step 4 of the projection (solver.divergence_cleaning): the exact projection of the corrected
// velocities (divergence_cleaning.cpp).
template <int D>
class DivergenceCleaning {
 public:
  explicit DivergenceCleaning(const LinearSolverOptions& options);
  // ops.divergence holds the corrected velocities' divergence at the same positions.
  void apply(StepContext<D>& sys, const ProjectionOperators<D>& ops, double t, double dt, double* y);
  const SolveReport& last() const { return last_; }
  std::string solverName() const { return solver_->name(); }
  // Totals (summary.json, checkpoints); seconds is kept by the projection, which times it.
  std::uint64_t iterations_total = 0;
  int iterations_max = 0;
  double residual_max = 0, seconds = 0;

 private:
  std::unique_ptr<LinearSolver> solver_;
  AssembledMatrix system_;
  std::vector<double> multiplier_;
  Eigen::VectorXd solution_;
  SolveReport last_;
};

}  // namespace vesph::isph
