#pragma once
// Sparse linear solvers for the pressure Poisson equation of ISPH (DESIGN.md "ISPH"). The
// matrix is not symmetric in general (the wall pressures are eliminated into the fluid rows,
// src/isph/projection.cpp), so the direct solvers are LU factorisations:
//   umfpack   SuiteSparse UMFPACK (multifrontal LU), through Eigen's UmfPackLU
//   klu       SuiteSparse KLU (left-looking LU for circuit-like matrices), Eigen's KLU
//   bicgstab  Eigen's BiCGSTAB with a diagonal (Jacobi) or incomplete-LU (ILUT) preconditioner,
//             warm-started from the previous step's pressure
// The direct solvers keep the symbolic analysis while the sparsity pattern is unchanged
// (between neighbour-list rebuilds, the pattern is that of the candidate list).
#include <Eigen/Sparse>
#include <memory>
#include <string>
#include <vector>

namespace vesph {

using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

struct LinearSolverOptions {
  std::string type = "bicgstab";           // umfpack | klu | bicgstab
  std::string preconditioner = "diagonal";  // bicgstab: diagonal | ilut
  double tolerance = 1e-8;                  // bicgstab: relative residual |Ax-b|/|b|
  int max_iterations = 2000;                // bicgstab
  double ilut_drop_tolerance = 1e-4;        // ilut: entries below this times the row norm are dropped
  int ilut_fill_factor = 10;                // ilut: fill-in per row relative to the matrix
};

struct SolveReport {
  bool ok = false;
  int iterations = 0;       // 1 for the direct solvers
  double residual = 0;      // |Ax - b| / |b| (0 when b = 0)
  std::string message;      // why it failed
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  virtual std::string name() const = 0;
  // Solves A x = b; x holds the initial guess on entry (used by the iterative solver).
  // pattern_changed: A's sparsity pattern differs from the previous call's.
  virtual SolveReport solve(const SparseRowMatrix& A, bool pattern_changed, const Eigen::VectorXd& b,
                            Eigen::VectorXd& x) = 0;
};

std::unique_ptr<LinearSolver> makeLinearSolver(const LinearSolverOptions& options);

struct LinearSolverInfo {
  std::string name, summary;
};
const std::vector<LinearSolverInfo>& linearSolverRegistry();

}  // namespace vesph
