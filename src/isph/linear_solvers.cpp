#include "vesph/isph/linear_solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/KLUSupport>
#include <Eigen/UmfPackSupport>
#include <cmath>
#include <sstream>

namespace vesph {
namespace {

using SparseColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

double relativeResidual(const SparseRowMatrix& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x) {
  const double nb = b.norm();
  const double nr = (A * x - b).norm();
  return nb > 0 ? nr / nb : nr;
}

// UMFPACK and KLU share Eigen's interface (analyzePattern / factorize / solve); both take a
// column-major matrix, so the row-major assembly is converted (O(nnz)).
template <class Factorisation>
class DirectSolver final : public LinearSolver {
 public:
  explicit DirectSolver(std::string name) : name_(std::move(name)) {}
  std::string name() const override { return name_; }

  SolveReport solve(const SparseRowMatrix& A, bool pattern_changed, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x) override {
    SolveReport r;
    column_major_ = A;
    if (pattern_changed || !analysed_) {
      lu_.analyzePattern(column_major_);
      analysed_ = lu_.info() == Eigen::Success;
      if (!analysed_) {
        r.message = name_ + ": symbolic analysis failed";
        return r;
      }
    }
    lu_.factorize(column_major_);
    if (lu_.info() != Eigen::Success) {
      r.message = name_ + ": the pressure matrix is singular or the factorisation failed (a fluid region with "
                          "no free surface and no pinned pressure?)";
      analysed_ = false;
      return r;
    }
    x = lu_.solve(b);
    r.iterations = 1;
    r.residual = relativeResidual(A, b, x);
    r.ok = lu_.info() == Eigen::Success && x.allFinite() && r.residual < 1e-6;
    if (!r.ok) {
      std::ostringstream os;
      os << name_ << ": the solve gave a relative residual of " << r.residual
         << " (the matrix is numerically singular)";
      r.message = os.str();
    }
    return r;
  }

 private:
  std::string name_;
  SparseColMatrix column_major_;
  Factorisation lu_;
  bool analysed_ = false;
};

template <class Preconditioner>
class BiCgStabSolver final : public LinearSolver {
 public:
  BiCgStabSolver(const LinearSolverOptions& o, std::string name) : options_(o), name_(std::move(name)) {
    solver_.setTolerance(o.tolerance);
    solver_.setMaxIterations(o.max_iterations);
    if constexpr (std::is_same_v<Preconditioner, Eigen::IncompleteLUT<double, int>>) {
      solver_.preconditioner().setDroptol(o.ilut_drop_tolerance);
      solver_.preconditioner().setFillfactor(o.ilut_fill_factor);
    }
  }
  std::string name() const override { return name_; }

  SolveReport solve(const SparseRowMatrix& A, bool, const Eigen::VectorXd& b, Eigen::VectorXd& x) override {
    SolveReport r;
    solver_.compute(A);
    if (solver_.info() != Eigen::Success) {
      r.message = name_ + ": the preconditioner could not be computed (zero pivot)";
      return r;
    }
    if (b.norm() == 0) {  // nothing to solve: the zero pressure is exact
      x.setZero();
      r.ok = true;
      return r;
    }
    Eigen::VectorXd guess = x;
    x = solver_.solveWithGuess(b, guess);
    r.iterations = static_cast<int>(solver_.iterations());
    r.residual = relativeResidual(A, b, x);
    r.ok = solver_.info() == Eigen::Success && x.allFinite();
    if (!r.ok) {
      std::ostringstream os;
      os << name_ << ": no convergence to the tolerance " << options_.tolerance << " in " << r.iterations
         << " iterations (solver.max_iterations = " << options_.max_iterations << "); relative residual " << r.residual;
      r.message = os.str();
    }
    return r;
  }

 private:
  LinearSolverOptions options_;
  std::string name_;
  Eigen::BiCGSTAB<SparseRowMatrix, Preconditioner> solver_;
};

}  // namespace

const std::vector<LinearSolverInfo>& linearSolverRegistry() {
  static const std::vector<LinearSolverInfo> registry = {
      {"umfpack", "SuiteSparse UMFPACK sparse LU (direct); symbolic analysis reused while the pattern holds"},
      {"klu", "SuiteSparse KLU sparse LU (direct); symbolic analysis reused while the pattern holds"},
      {"bicgstab", "Eigen BiCGSTAB (iterative; preconditioner diagonal | ilut; tolerance, max_iterations)"},
  };
  return registry;
}

std::unique_ptr<LinearSolver> makeLinearSolver(const LinearSolverOptions& o) {
  if (o.type == "umfpack") return std::make_unique<DirectSolver<Eigen::UmfPackLU<SparseColMatrix>>>("umfpack");
  if (o.type == "klu") return std::make_unique<DirectSolver<Eigen::KLU<SparseColMatrix>>>("klu");
  if (o.type == "bicgstab") {
    if (o.preconditioner == "ilut")
      return std::make_unique<BiCgStabSolver<Eigen::IncompleteLUT<double, int>>>(o, "bicgstab+ilut");
    return std::make_unique<BiCgStabSolver<Eigen::DiagonalPreconditioner<double>>>(o, "bicgstab+diagonal");
  }
  throw std::logic_error("unknown linear solver " + o.type);
}

}  // namespace vesph
