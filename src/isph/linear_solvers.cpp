#include "vesph/isph/linear_solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/KLUSupport>
#include <Eigen/UmfPackSupport>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unsupported/Eigen/IterativeSolvers>

#include "amg_solver.hpp"
#include "vesph/io/config.hpp"

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

// Eigen's Krylov solvers (BiCGSTAB, CG, GMRES) with a diagonal or ILUT preconditioner; they share
// the IterativeSolverBase interface (compute / solveWithGuess / iterations / info).
template <class KrylovSolver>
class EigenKrylovSolver final : public LinearSolver {
  static constexpr bool kIsGmres =
      std::is_same_v<KrylovSolver, Eigen::GMRES<SparseRowMatrix, typename KrylovSolver::Preconditioner>>;

 public:
  EigenKrylovSolver(const LinearSolverOptions& o, std::string name) : options_(o), name_(std::move(name)) {
    solver_.setTolerance(o.tolerance);
    solver_.setMaxIterations(o.max_iterations);
    if constexpr (std::is_same_v<typename KrylovSolver::Preconditioner, Eigen::IncompleteLUT<double, int>>) {
      solver_.preconditioner().setDroptol(o.ilut_drop_tolerance);
      solver_.preconditioner().setFillfactor(o.ilut_fill_factor);
    }
    if constexpr (kIsGmres) solver_.set_restart(o.gmres_restart);
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
    if constexpr (kIsGmres) {
      // Eigen's GMRES does not stop on a guess that already solves the system (it reports no
      // convergence after max_iterations): test it first.
      r.residual = relativeResidual(A, b, x);
      if (r.residual <= options_.tolerance) {
        r.ok = true;
        return r;
      }
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
  KrylovSolver solver_;
};

template <template <class, class> class Krylov>
std::unique_ptr<LinearSolver> makeEigenKrylov(const LinearSolverOptions& o, const std::string& name) {
  using Ilut = Eigen::IncompleteLUT<double, int>;
  using Diagonal = Eigen::DiagonalPreconditioner<double>;
  if (o.preconditioner == "ilut") return std::make_unique<EigenKrylovSolver<Krylov<SparseRowMatrix, Ilut>>>(o, name + "+ilut");
  return std::make_unique<EigenKrylovSolver<Krylov<SparseRowMatrix, Diagonal>>>(o, name + "+diagonal");
}

// Eigen's ConjugateGradient takes the triangle it reads as a template argument: both, since the
// matrix is stored whole (and is symmetric only for some forms of the operator).
template <class M, class P>
using FullConjugateGradient = Eigen::ConjugateGradient<M, Eigen::Lower | Eigen::Upper, P>;
template <class M, class P>
using Gmres = Eigen::GMRES<M, P>;
template <class M, class P>
using BiCgStab = Eigen::BiCGSTAB<M, P>;

bool isKrylov(const std::string& type) { return type == "bicgstab" || type == "cg" || type == "gmres"; }

}  // namespace

LinearSolverOptions readLinearSolverOptions(ConfigTable& cfg) {
  LinearSolverOptions o;
  // Defaults: BiCGSTAB with the AMG preconditioner, the fastest choice measured from 10 000 to
  // 1 000 000 unknowns and the one every ISPH test passes with (docs/performance.md, "ISPH
  // pressure solve with algebraic multigrid"); the hierarchy kept for up to 10 solves while the
  // pattern holds (amg_setup_interval): the same iterations as a new one every solve on the
  // tank and the die swell, at half the solve time (a failed solve with a kept hierarchy is
  // retried with a new one, src/isph/amg_solver.cpp).
  o.type = cfg.choice("linear_solver", "bicgstab", {"umfpack", "klu", "bicgstab", "cg", "gmres"});
  if (isKrylov(o.type)) {
    o.preconditioner = cfg.choice("preconditioner", "amg", {"diagonal", "ilut", "amg"});
    o.tolerance = cfg.numberIn("tolerance", 1e-8, 1e-15, 1e-1, "relative residual");
    o.max_iterations = static_cast<int>(cfg.integer("max_iterations", 2000, 1, 1000000));
    if (o.preconditioner == "ilut") {
      o.ilut_drop_tolerance = cfg.numberIn("ilut_drop_tolerance", 1e-4, 0.0, 1.0);
      o.ilut_fill_factor = static_cast<int>(cfg.integer("ilut_fill_factor", 10, 1, 1000));
    }
    if (o.type == "gmres") o.gmres_restart = static_cast<int>(cfg.integer("gmres_restart", 30, 1, 10000));
    if (o.preconditioner == "amg") {
      o.amg_setup_interval = static_cast<int>(cfg.integer("amg_setup_interval", 10, 1, 1000000));
      o.amg_strong_threshold = cfg.numberIn("amg_strong_threshold", 0.25, 0.0, 1.0);
    }
  } else {
    for (const char* key : {"preconditioner", "tolerance", "max_iterations", "ilut_drop_tolerance", "ilut_fill_factor",
                            "gmres_restart", "amg_setup_interval", "amg_strong_threshold"})
      if (cfg.has(key))
        cfg.fail(key, "no " + std::string(key) + " for the direct solver '" + o.type +
                          "' (it is a key of linear_solver = \"bicgstab\", \"cg\" or \"gmres\")");
  }
  return o;
}

SolveReport LinearSolver::solveAcross(const SparseRowMatrix&, bool, const DistributedRows&, const Eigen::VectorXd&,
                                      Eigen::VectorXd&) {
  throw std::logic_error("linear solver " + name() + " cannot solve across processes (preconditioner = \"amg\" can)");
}

const std::vector<LinearSolverInfo>& linearSolverRegistry() {
  static const std::vector<LinearSolverInfo> registry = {
      {"umfpack", "SuiteSparse UMFPACK sparse LU (direct); symbolic analysis reused while the pattern holds"},
      {"klu", "SuiteSparse KLU sparse LU (direct); symbolic analysis reused while the pattern holds"},
      {"bicgstab", "BiCGSTAB (iterative; preconditioner diagonal | ilut (Eigen) | amg (hypre BoomerAMG))"},
      {"cg", "conjugate gradients (iterative, symmetric matrices; preconditioner diagonal | ilut | amg)"},
      {"gmres", "restarted GMRES (iterative; preconditioner diagonal | ilut | amg; gmres_restart)"},
  };
  return registry;
}

std::unique_ptr<LinearSolver> makeLinearSolver(const LinearSolverOptions& o) {
  if (o.type == "umfpack") return std::make_unique<DirectSolver<Eigen::UmfPackLU<SparseColMatrix>>>("umfpack");
  if (o.type == "klu") return std::make_unique<DirectSolver<Eigen::KLU<SparseColMatrix>>>("klu");
  if (!isKrylov(o.type)) throw std::logic_error("unknown linear solver " + o.type);
  if (o.preconditioner == "amg") return makeAmgSolver(o);
  if (o.type == "bicgstab") return makeEigenKrylov<BiCgStab>(o, "bicgstab");
  if (o.type == "cg") return makeEigenKrylov<FullConjugateGradient>(o, "cg");
  return makeEigenKrylov<Gmres>(o, "gmres");
}

}  // namespace vesph
