// Algebraic multigrid for the pressure Poisson equation: hypre's Krylov solvers (BiCGSTAB, PCG,
// GMRES) preconditioned by one BoomerAMG V-cycle (Henson & Yang 2002, "BoomerAMG: a parallel
// algebraic multigrid solver and preconditioner"; docs/theory.md §10 for the pressure system).
//
// hypre (Debian's libhypre-dev) is built against MPI: every hypre object lives on a
// communicator, so the first AMG solver initialises MPI (MPI_Init_thread, one process: a
// singleton without mpirun) on MPI_COMM_SELF and finalises it at exit. The solvers without AMG
// never touch MPI. hypre's sequential build would avoid this, but Debian ships only the MPI one.
//
// The matrix is copied into a hypre ParCSR matrix once per sparsity pattern (hypre keeps the
// diagonal first in each row, so a map from hypre's entries to the assembly's is built with it);
// while the pattern holds, the values are gathered through that map in place, in parallel, and
// the AMG hierarchy (the set-up, several solves' worth of time) is kept for up to
// amg_setup_interval solves: the fine level then smooths with the current matrix, the coarse
// levels lag (docs/performance.md measures the trade-off).
#include "amg_solver.hpp"

#include "vesph/isph/amg_preconditioner.hpp"
#include "vesph/parallel/communicator.hpp"
#include "vesph/time/integrator.hpp"

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <_hypre_parcsr_mv.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <mutex>
#include <sstream>
#include <stdexcept>

namespace vesph {
namespace {

// hypre is initialised once per process, at the first AMG solve (MPI first, if nothing started
// it: parallel/communicator.hpp); finalised at exit, before MPI (atexit runs in reverse order).
void initialiseHypre() {
  static std::once_flag once;
  std::call_once(once, [] {
    try {
      ensureMpiInitialised();
    } catch (const std::exception&) {
      throw std::runtime_error("preconditioner = \"amg\": MPI could not be initialised (hypre needs it)");
    }
    HYPRE_Init();
    std::atexit([] { HYPRE_Finalize(); });
  });
}

// The Krylov solver's set-up calls the preconditioner's: a no-op, so that the hierarchy is
// built only when this class decides (AmgKrylovSolver::solve).
HYPRE_Int keepHierarchy(HYPRE_Solver, HYPRE_ParCSRMatrix, HYPRE_ParVector, HYPRE_ParVector) { return 0; }

double* vectorData(HYPRE_ParVector v) { return hypre_VectorData(hypre_ParVectorLocalVector(reinterpret_cast<hypre_ParVector*>(v))); }

class AmgKrylovSolver final : public LinearSolver {
 public:
  // MPI and hypre start at the first solve, not here: `vesph check` of an ISPH scene builds the
  // solver without solving and never starts MPI.
  explicit AmgKrylovSolver(const LinearSolverOptions& o) : options_(o), name_(o.type + "+amg") {}
  ~AmgKrylovSolver() override { release(); }
  AmgKrylovSolver(const AmgKrylovSolver&) = delete;
  AmgKrylovSolver& operator=(const AmgKrylovSolver&) = delete;
  std::string name() const override { return name_; }
  void prepare() override { initialiseHypre(); }

  SolveReport solve(const SparseRowMatrix& A, bool pattern_changed, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x) override {
    SolveReport r;
    const int n = static_cast<int>(A.rows());
    if (b.norm() == 0) {  // nothing to solve: the zero pressure is exact
      x.setZero();
      r.ok = true;
      return r;
    }
    initialiseHypre();
    if (pattern_changed || !matrix_ || n != size_) build(A);
    // The values (in place, through the map), and the rows that are all zero: a particle with
    // no neighbour among the unknowns, the row 0 = b_i. With b_i = 0 it is p_i = 0 (a unit
    // diagonal, which AMG needs); otherwise the system has no solution.
    const double* values = A.valuePtr();
    double* data = hypre_CSRMatrixData(diag_);
    const int* row_start = hypre_CSRMatrixI(diag_);
    const int entries = static_cast<int>(source_.size());
    int bad_row = -1;
#pragma omp parallel for schedule(static) if (entries > 100000)
    for (int k = 0; k < entries; ++k) data[k] = values[source_[k]];
#pragma omp parallel for schedule(static) reduction(max : bad_row) if (n > 10000)
    for (int i = 0; i < n; ++i) {
      if (data[row_start[i]] != 0.0) continue;  // hypre stores the diagonal first
      bool empty = true;
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) empty = empty && data[k] == 0.0;
      if (empty && b[i] == 0.0)
        data[row_start[i]] = 1.0;
      else
        bad_row = std::max(bad_row, i);
    }
    if (bad_row >= 0) {
      std::ostringstream os;
      os << name_ << ": the pressure matrix is singular (unknown " << bad_row
         << " has a zero diagonal: an equation without its own pressure)";
      r.message = os.str();
      return r;
    }
    std::copy(b.data(), b.data() + n, vectorData(b_));
    const bool keep = solves_since_setup_ > 0 && solves_since_setup_ < options_.amg_setup_interval;
    if (keep) guess_ = x;  // for a second attempt
    else setUp();
    ++solves_since_setup_;
    r = krylovSolve(A, b, x);
    if (!r.ok && keep) {
      // The kept hierarchy may no longer fit the matrix (its smoother's scaling is the old
      // matrix's): once more with a fresh one before reporting a failure.
      x = guess_;
      setUp();
      ++solves_since_setup_;
      r = krylovSolve(A, b, x);
    }
    if (!r.ok) solves_since_setup_ = 0;  // a fresh hierarchy for the next solve
    return r;
  }

 private:
  void setUp() {
    HYPRE_BoomerAMGSetup(amg_, matrix_, b_, x_);
    HYPRE_ClearAllErrors();
    solves_since_setup_ = 0;
  }

  // hypre's Krylov solver from the guess x; x the result, checked.
  SolveReport krylovSolve(const SparseRowMatrix& A, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    SolveReport r;
    const int n = static_cast<int>(A.rows());
    std::copy(x.data(), x.data() + n, vectorData(x_));
    HYPRE_Int error = 0, iterations = 0;
    if (options_.type == "bicgstab") {
      error = HYPRE_ParCSRBiCGSTABSolve(krylov_, matrix_, b_, x_);
      HYPRE_ParCSRBiCGSTABGetNumIterations(krylov_, &iterations);
    } else if (options_.type == "cg") {
      error = HYPRE_ParCSRPCGSolve(krylov_, matrix_, b_, x_);
      HYPRE_ParCSRPCGGetNumIterations(krylov_, &iterations);
    } else {
      error = HYPRE_ParCSRGMRESSolve(krylov_, matrix_, b_, x_);
      HYPRE_ParCSRGMRESGetNumIterations(krylov_, &iterations);
    }
    HYPRE_ClearAllErrors();
    std::copy(vectorData(x_), vectorData(x_) + n, x.data());
    r.iterations = iterations;
    r.residual = (A * x - b).norm() / b.norm();
    // hypre's own test is on its recurrence residual; the true one is checked too (within a
    // factor 10 of the tolerance, the recurrence's usual drift), so that a preconditioner
    // that broke down never passes for a solution.
    r.ok = error == 0 && x.allFinite() && r.residual <= 10 * options_.tolerance;
    if (!r.ok) {
      std::ostringstream os;
      if (!x.allFinite())
        os << name_ << ": the solve broke down (non-finite values after " << r.iterations
           << " iterations: a singular pressure matrix?)";
      else
        os << name_ << ": no convergence to the tolerance " << options_.tolerance << " in " << r.iterations
           << " iterations (solver.max_iterations = " << options_.max_iterations << "); relative residual "
           << r.residual;
      r.message = os.str();
    }
    return r;
  }

  // A new pattern: hypre's matrix, vectors, hierarchy and Krylov solver anew.
  void build(const SparseRowMatrix& A) {
    release();
    const int n = size_ = static_cast<int>(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    row_lengths_.resize(static_cast<std::size_t>(n));
    row_numbers_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      row_lengths_[static_cast<std::size_t>(i)] = outer[i + 1] - outer[i];
      row_numbers_[static_cast<std::size_t>(i)] = i;
    }
    HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, n - 1, 0, n - 1, &ij_);
    HYPRE_IJMatrixSetObjectType(ij_, HYPRE_PARCSR);
    HYPRE_IJMatrixSetRowSizes(ij_, row_lengths_.data());
    HYPRE_IJMatrixInitialize(ij_);
    HYPRE_IJMatrixSetValues(ij_, n, row_lengths_.data(), row_numbers_.data(), inner, A.valuePtr());
    HYPRE_IJMatrixAssemble(ij_);
    HYPRE_IJMatrixGetObject(ij_, reinterpret_cast<void**>(&matrix_));
    diag_ = hypre_ParCSRMatrixDiag(reinterpret_cast<hypre_ParCSRMatrix*>(matrix_));
    // hypre's entry k of row i holds the assembly's entry with the same column (a binary search
    // in the assembly's sorted row).
    const int* hi = hypre_CSRMatrixI(diag_);
    const int* hj = hypre_CSRMatrixJ(diag_);
    if (hypre_CSRMatrixNumNonzeros(diag_) != A.nonZeros())
      throw std::logic_error("amg: hypre's copy of the pressure matrix has a different number of entries");
    source_.resize(static_cast<std::size_t>(A.nonZeros()));
#pragma omp parallel for schedule(static) if (n > 10000)
    for (int i = 0; i < n; ++i)
      for (int k = hi[i]; k < hi[i + 1]; ++k)
        source_[static_cast<std::size_t>(k)] = static_cast<int>(std::lower_bound(inner + outer[i], inner + outer[i + 1], hj[k]) - inner);

    HYPRE_ParVectorCreate(MPI_COMM_SELF, n, nullptr, &b_);
    HYPRE_ParVectorInitialize(b_);
    HYPRE_ParVectorCreate(MPI_COMM_SELF, n, nullptr, &x_);
    HYPRE_ParVectorInitialize(x_);

    // One V-cycle per application (MaxIter 1, no tolerance). hypre's defaults otherwise (2.26:
    // HMIS coarsening, extended+i interpolation truncated to 4 entries, l1-Gauss-Seidel
    // smoothing): they suit non-symmetric, M-matrix-like Poisson operators.
    HYPRE_BoomerAMGCreate(&amg_);
    HYPRE_BoomerAMGSetPrintLevel(amg_, 0);
    HYPRE_BoomerAMGSetMaxIter(amg_, 1);
    HYPRE_BoomerAMGSetTol(amg_, 0.0);
    HYPRE_BoomerAMGSetStrongThreshold(amg_, options_.amg_strong_threshold);
    if (options_.type == "bicgstab") {
      HYPRE_ParCSRBiCGSTABCreate(MPI_COMM_SELF, &krylov_);
      HYPRE_ParCSRBiCGSTABSetTol(krylov_, options_.tolerance);
      HYPRE_ParCSRBiCGSTABSetMaxIter(krylov_, options_.max_iterations);
      HYPRE_ParCSRBiCGSTABSetPrecond(krylov_, HYPRE_BoomerAMGSolve, keepHierarchy, amg_);
      HYPRE_ParCSRBiCGSTABSetup(krylov_, matrix_, b_, x_);
    } else if (options_.type == "cg") {
      HYPRE_ParCSRPCGCreate(MPI_COMM_SELF, &krylov_);
      HYPRE_ParCSRPCGSetTol(krylov_, options_.tolerance);
      HYPRE_ParCSRPCGSetMaxIter(krylov_, options_.max_iterations);
      HYPRE_ParCSRPCGSetTwoNorm(krylov_, 1);  // |r| / |b|, as the other solvers
      HYPRE_ParCSRPCGSetPrecond(krylov_, HYPRE_BoomerAMGSolve, keepHierarchy, amg_);
      HYPRE_ParCSRPCGSetup(krylov_, matrix_, b_, x_);
    } else {
      HYPRE_ParCSRGMRESCreate(MPI_COMM_SELF, &krylov_);
      HYPRE_ParCSRGMRESSetKDim(krylov_, options_.gmres_restart);
      HYPRE_ParCSRGMRESSetTol(krylov_, options_.tolerance);
      HYPRE_ParCSRGMRESSetMaxIter(krylov_, options_.max_iterations);
      HYPRE_ParCSRGMRESSetPrecond(krylov_, HYPRE_BoomerAMGSolve, keepHierarchy, amg_);
      HYPRE_ParCSRGMRESSetup(krylov_, matrix_, b_, x_);
    }
    HYPRE_ClearAllErrors();
    solves_since_setup_ = 0;
  }

  void release() {
    if (krylov_) {
      if (options_.type == "bicgstab") HYPRE_ParCSRBiCGSTABDestroy(krylov_);
      else if (options_.type == "cg") HYPRE_ParCSRPCGDestroy(krylov_);
      else HYPRE_ParCSRGMRESDestroy(krylov_);
    }
    if (amg_) HYPRE_BoomerAMGDestroy(amg_);
    if (b_) HYPRE_ParVectorDestroy(b_);
    if (x_) HYPRE_ParVectorDestroy(x_);
    if (ij_) HYPRE_IJMatrixDestroy(ij_);
    krylov_ = amg_ = nullptr;
    b_ = x_ = nullptr;
    ij_ = nullptr;
    matrix_ = nullptr;
    diag_ = nullptr;
  }

  LinearSolverOptions options_;
  std::string name_;
  HYPRE_IJMatrix ij_ = nullptr;
  HYPRE_ParCSRMatrix matrix_ = nullptr;  // owned by ij_
  hypre_CSRMatrix* diag_ = nullptr;      // matrix_'s local block (all of it: one process)
  HYPRE_ParVector b_ = nullptr, x_ = nullptr;
  HYPRE_Solver amg_ = nullptr, krylov_ = nullptr;
  std::vector<int> row_lengths_, row_numbers_;
  std::vector<int> source_;  // hypre's entry k = the assembly's entry source_[k]
  Eigen::VectorXd guess_;    // the initial guess, kept for a second attempt
  int size_ = -1;
  int solves_since_setup_ = 0;
};

}  // namespace

struct AmgPreconditioner::Hypre {
  HYPRE_IJMatrix ij = nullptr;
  HYPRE_ParCSRMatrix matrix = nullptr;  // owned by ij
  HYPRE_ParVector b = nullptr, x = nullptr;
  HYPRE_Solver amg = nullptr;
  int n = 0;
  std::vector<int> row_lengths, row_numbers;

  void release() {
    if (amg) HYPRE_BoomerAMGDestroy(amg);
    if (b) HYPRE_ParVectorDestroy(b);
    if (x) HYPRE_ParVectorDestroy(x);
    if (ij) HYPRE_IJMatrixDestroy(ij);
    amg = nullptr;
    b = x = nullptr;
    ij = nullptr;
    matrix = nullptr;
    n = 0;
  }
  ~Hypre() { release(); }
};

AmgPreconditioner::AmgPreconditioner() : hypre_(std::make_unique<Hypre>()) {}
AmgPreconditioner::~AmgPreconditioner() = default;
int AmgPreconditioner::size() const { return hypre_->n; }

void AmgPreconditioner::setUp(const CsrMatrix& A) {
  initialiseHypre();
  Hypre& h = *hypre_;
  h.release();
  const int n = h.n = A.rows();
  h.row_lengths.resize(static_cast<std::size_t>(n));
  h.row_numbers.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    h.row_lengths[static_cast<std::size_t>(i)] = A.row_start[static_cast<std::size_t>(i) + 1] - A.row_start[static_cast<std::size_t>(i)];
    h.row_numbers[static_cast<std::size_t>(i)] = i;
  }
  HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, n - 1, 0, n - 1, &h.ij);
  HYPRE_IJMatrixSetObjectType(h.ij, HYPRE_PARCSR);
  HYPRE_IJMatrixSetRowSizes(h.ij, h.row_lengths.data());
  HYPRE_IJMatrixInitialize(h.ij);
  HYPRE_IJMatrixAddToValues(h.ij, n, h.row_lengths.data(), h.row_numbers.data(), A.column.data(), A.value.data());
  HYPRE_IJMatrixAssemble(h.ij);
  HYPRE_IJMatrixGetObject(h.ij, reinterpret_cast<void**>(&h.matrix));
  HYPRE_ParVectorCreate(MPI_COMM_SELF, n, nullptr, &h.b);
  HYPRE_ParVectorInitialize(h.b);
  HYPRE_ParVectorCreate(MPI_COMM_SELF, n, nullptr, &h.x);
  HYPRE_ParVectorInitialize(h.x);
  // One V-cycle per application, hypre's defaults otherwise (as the pressure solvers' AMG).
  HYPRE_BoomerAMGCreate(&h.amg);
  HYPRE_BoomerAMGSetPrintLevel(h.amg, 0);
  HYPRE_BoomerAMGSetMaxIter(h.amg, 1);
  HYPRE_BoomerAMGSetTol(h.amg, 0.0);
  HYPRE_BoomerAMGSetup(h.amg, h.matrix, h.b, h.x);
  HYPRE_ClearAllErrors();
}

void AmgPreconditioner::apply(const double* r, double* z) {
  Hypre& h = *hypre_;
  if (!h.amg) throw std::logic_error("AmgPreconditioner::apply before setUp");
  std::copy(r, r + h.n, vectorData(h.b));
  std::fill(vectorData(h.x), vectorData(h.x) + h.n, 0.0);
  HYPRE_BoomerAMGSolve(h.amg, h.matrix, h.b, h.x);
  HYPRE_ClearAllErrors();
  std::copy(vectorData(h.x), vectorData(h.x) + h.n, z);
}

std::unique_ptr<LinearSolver> makeAmgSolver(const LinearSolverOptions& options) {
  return std::make_unique<AmgKrylovSolver>(options);
}

}  // namespace vesph
