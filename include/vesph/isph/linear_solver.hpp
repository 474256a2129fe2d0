#pragma once
// Sparse linear solvers for the pressure Poisson equation of ISPH (docs/architecture.md, "ISPH";
// docs/theory.md). The matrix is not symmetric in general (the wall pressures are eliminated
// into the fluid rows, src/isph/projection.cpp), so the direct solvers are LU factorisations:
//   umfpack   SuiteSparse UMFPACK (multifrontal LU), through Eigen's UmfPackLU
//   klu       SuiteSparse KLU (left-looking LU for circuit-like matrices), Eigen's KLU
// and the Krylov solvers are warm-started from the previous step's pressure:
//   bicgstab  BiCGSTAB            } preconditioner = "diagonal" (Jacobi) or "ilut" (incomplete LU):
//   cg        conjugate gradients } Eigen's solvers (cg and gmres in Eigen's unsupported module);
//   gmres     restarted GMRES     } preconditioner = "amg": hypre's Krylov solver preconditioned
//                                   by one BoomerAMG V-cycle (src/isph/amg_solver.cpp)
// The direct solvers keep the symbolic analysis while the sparsity pattern is unchanged
// (between neighbour-list rebuilds, the pattern is that of the candidate list); the AMG
// preconditioner keeps its hierarchy while the pattern is unchanged, for at most
// amg_setup_interval solves (its coarse levels then lag the matrix's values).
#include <Eigen/Sparse>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vesph {

class ConfigTable;

using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

struct LinearSolverOptions {
  std::string type = "bicgstab";           // umfpack | klu | bicgstab | cg | gmres
  std::string preconditioner = "diagonal";  // Krylov solvers: diagonal | ilut | amg (scenes default to amg: readLinearSolverOptions)
  double tolerance = 1e-8;                  // Krylov: relative residual |Ax-b|/|b|
  int max_iterations = 2000;                // Krylov
  double ilut_drop_tolerance = 1e-4;        // ilut: entries below this times the row norm are dropped
  int ilut_fill_factor = 10;                // ilut: fill-in per row relative to the matrix
  int gmres_restart = 30;                   // gmres: Krylov vectors kept before a restart
  int amg_setup_interval = 1;               // amg: solves that share one hierarchy (pattern unchanged; scenes default to 10)
  double amg_strong_threshold = 0.25;       // amg: BoomerAMG's strength of connection
};

// Reads solver.linear_solver, solver.preconditioner and their sub-keys (the keys are listed in
// docs/user-guide.md, "[solver]"); keys that do not belong to the chosen solver are errors.
LinearSolverOptions readLinearSolverOptions(ConfigTable& solver_table);

struct SolveReport {
  bool ok = false;
  int iterations = 0;       // 1 for the direct solvers
  double residual = 0;      // |Ax - b| / |b| (0 when b = 0)
  std::string message;      // why it failed
};

// A pressure system spread over the processes of a distributed run: this process holds the
// rows [first_row, first_row + A.rows()) of a system of global_rows unknowns, and A's columns
// are local: column c is the global unknown column_global[c] (the process's own rows first, so
// column_global[c] = first_row + c for c < A.rows(); then the unknowns of its ghosts).
struct DistributedRows {
  const void* communicator = nullptr;  // points to the run's MPI_Comm
  std::int64_t first_row = 0, global_rows = 0;
  std::vector<std::int64_t> column_global;
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  virtual std::string name() const = 0;
  // Solves A x = b; x holds the initial guess on entry (used by the iterative solvers).
  // pattern_changed: A's sparsity pattern differs from the previous call's.
  virtual SolveReport solve(const SparseRowMatrix& A, bool pattern_changed, const Eigen::VectorXd& b,
                            Eigen::VectorXd& x) = 0;
  // Starts what the solver needs once per process before its first solve (the AMG solver: MPI
  // and hypre), so that the first solve's time is the solve's; a run calls it when it is about
  // to solve (never `vesph check`).
  virtual void prepare() {}
  // Whether solveAcross works (the hypre solvers: preconditioner = "amg").
  virtual bool solvesAcrossProcesses() const { return false; }
  // The distributed solve: every process calls it together with its rows (A: its rows, local
  // columns; b, x: its rows). The report is the whole system's, the same on every process.
  virtual SolveReport solveAcross(const SparseRowMatrix& A, bool pattern_changed, const DistributedRows& rows,
                                  const Eigen::VectorXd& b, Eigen::VectorXd& x);
};

std::unique_ptr<LinearSolver> makeLinearSolver(const LinearSolverOptions& options);

struct LinearSolverInfo {
  std::string name, summary;
};
const std::vector<LinearSolverInfo>& linearSolverRegistry();

}  // namespace vesph
