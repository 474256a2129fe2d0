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
#include <cstdint>
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
  bool solvesAcrossProcesses() const override { return true; }

  SolveReport solve(const SparseRowMatrix& A, bool pattern_changed, const Eigen::VectorXd& b,
                    Eigen::VectorXd& x) override {
    if (b.norm() == 0) {  // nothing to solve: the zero pressure is exact
      x.setZero();
      return SolveReport{true, 0, 0.0, {}};
    }
    initialiseHypre();
    across_ = nullptr;
    if (pattern_changed || !matrix_ || comm_ != MPI_COMM_SELF || A.rows() != size_) build(A, nullptr);
    return solveBuilt(A, b, x);
  }

  // The same across the processes of a distributed run (LinearSolver::solveAcross): hypre's
  // matrix, vectors and solvers live on the run's communicator, each process holding its rows;
  // every decision (nothing to solve, a new pattern, a singular row, success) is agreed on.
  SolveReport solveAcross(const SparseRowMatrix& A, bool pattern_changed, const DistributedRows& rows,
                          const Eigen::VectorXd& b, Eigen::VectorXd& x) override {
    initialiseHypre();
    const MPI_Comm comm = *static_cast<const MPI_Comm*>(rows.communicator);
    const bool rebuild = pattern_changed || !matrix_ || comm_ != comm || A.rows() != size_;
    double agreed[2] = {b.squaredNorm(), rebuild ? 1.0 : 0.0};
    MPI_Allreduce(MPI_IN_PLACE, agreed, 2, MPI_DOUBLE, MPI_SUM, comm);
    if (agreed[0] == 0) {
      x.setZero();
      return SolveReport{true, 0, 0.0, {}};
    }
    across_ = &rows;
    if (agreed[1] > 0) build(A, &rows);
    SolveReport r = solveBuilt(A, b, x);
    across_ = nullptr;
    return r;
  }

 private:
  MPI_Comm communicator() const { return across_ ? *static_cast<const MPI_Comm*>(across_->communicator) : MPI_COMM_SELF; }

  // Solves with the matrix built (build()) for A's pattern.
  SolveReport solveBuilt(const SparseRowMatrix& A, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
    SolveReport r;
    const int n = static_cast<int>(A.rows());
    // The values (in place, through the maps), and the rows that are all zero: a particle with
    // no neighbour among the unknowns, the row 0 = b_i. With b_i = 0 it is p_i = 0 (a unit
    // diagonal, which AMG needs); otherwise the system has no solution.
    const double* values = A.valuePtr();
    double* data = hypre_CSRMatrixData(diag_);
    const int* row_start = hypre_CSRMatrixI(diag_);
    const int entries = static_cast<int>(source_.size());
#pragma omp parallel for schedule(static) if (entries > 100000)
    for (int k = 0; k < entries; ++k) data[k] = values[source_[k]];
    double* offd_data = offd_ ? hypre_CSRMatrixData(offd_) : nullptr;
    const int* offd_start = offd_ ? hypre_CSRMatrixI(offd_) : nullptr;
    const int offd_entries = static_cast<int>(source_offd_.size());
    for (int k = 0; k < offd_entries; ++k) offd_data[k] = values[source_offd_[k]];
    int bad_row = -1;
#pragma omp parallel for schedule(static) reduction(max : bad_row) if (n > 10000)
    for (int i = 0; i < n; ++i) {
      if (data[row_start[i]] != 0.0) continue;  // hypre stores the diagonal first
      bool empty = true;
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) empty = empty && data[k] == 0.0;
      if (offd_data)
        for (int k = offd_start[i]; k < offd_start[i + 1]; ++k) empty = empty && offd_data[k] == 0.0;
      if (empty && b[i] == 0.0)
        data[row_start[i]] = 1.0;
      else
        bad_row = std::max(bad_row, i + static_cast<int>(first_row_));
    }
    if (across_) MPI_Allreduce(MPI_IN_PLACE, &bad_row, 1, MPI_INT, MPI_MAX, communicator());
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

  void setUp() {
    HYPRE_BoomerAMGSetup(amg_, matrix_, b_, x_);
    HYPRE_ClearAllErrors();
    solves_since_setup_ = 0;
  }

  // |b - A x| / |b| of the whole system: serially from the assembled matrix, across processes
  // from hypre's copy (the same values) and global inner products.
  double trueResidual(const SparseRowMatrix& A, const Eigen::VectorXd& b, const Eigen::VectorXd& x) {
    if (!across_) return (A * x - b).norm() / b.norm();
    HYPRE_ParVectorCopy(b_, r_);
    HYPRE_ParCSRMatrixMatvec(-1.0, matrix_, x_, 1.0, r_);
    double rr = 0, bb = 0;
    HYPRE_ParVectorInnerProd(r_, r_, &rr);
    HYPRE_ParVectorInnerProd(b_, b_, &bb);
    return std::sqrt(rr / bb);
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
    r.residual = trueResidual(A, b, x);
    // hypre's own test is on its recurrence residual; the true one is checked too (within a
    // factor 10 of the tolerance, the recurrence's usual drift), so that a preconditioner
    // that broke down never passes for a solution. Across processes a non-finite value
    // anywhere makes the global residual non-finite everywhere.
    int agreed[2] = {x.allFinite() ? 1 : 0, error == 0 ? 1 : 0};  // finite, hypre's own success
    if (across_) MPI_Allreduce(MPI_IN_PLACE, agreed, 2, MPI_INT, MPI_MIN, communicator());
    const bool finite = agreed[0] != 0;
    r.ok = agreed[1] != 0 && finite && r.residual <= 10 * options_.tolerance;
    if (!r.ok) {
      std::ostringstream os;
      if (!finite)
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

  HYPRE_ParVector makeVector(MPI_Comm comm, int n, HYPRE_IJVector& ij) {
    HYPRE_IJVectorCreate(comm, static_cast<HYPRE_BigInt>(first_row_), static_cast<HYPRE_BigInt>(first_row_ + n - 1), &ij);
    HYPRE_IJVectorSetObjectType(ij, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(ij);
    HYPRE_IJVectorAssemble(ij);
    HYPRE_ParVector v = nullptr;
    HYPRE_IJVectorGetObject(ij, reinterpret_cast<void**>(&v));
    return v;
  }

  // A new pattern: hypre's matrix, vectors, hierarchy and Krylov solver anew (across: on the
  // run's communicator, this process's rows, global columns).
  void build(const SparseRowMatrix& A, const DistributedRows* across) {
    release();
    const MPI_Comm comm = communicator();
    comm_ = comm;
    first_row_ = across ? across->first_row : 0;
    const int n = size_ = static_cast<int>(A.rows());
    const int* outer = A.outerIndexPtr();
    const int* inner = A.innerIndexPtr();
    row_lengths_.resize(static_cast<std::size_t>(n));
    row_numbers_.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      row_lengths_[static_cast<std::size_t>(i)] = outer[i + 1] - outer[i];
      row_numbers_[static_cast<std::size_t>(i)] = static_cast<HYPRE_BigInt>(first_row_ + i);
    }
    // The columns as hypre numbers them: global across processes.
    const std::size_t nnz = static_cast<std::size_t>(A.nonZeros());
    columns_.resize(nnz);
    for (std::size_t e = 0; e < nnz; ++e)
      columns_[e] = static_cast<HYPRE_BigInt>(across ? across->column_global[static_cast<std::size_t>(inner[e])] : inner[e]);
    const HYPRE_BigInt lo = static_cast<HYPRE_BigInt>(first_row_), hi_row = static_cast<HYPRE_BigInt>(first_row_ + n - 1);
    HYPRE_IJMatrixCreate(comm, lo, hi_row, lo, hi_row, &ij_);
    HYPRE_IJMatrixSetObjectType(ij_, HYPRE_PARCSR);
    HYPRE_IJMatrixSetRowSizes(ij_, row_lengths_.data());
    HYPRE_IJMatrixInitialize(ij_);
    HYPRE_IJMatrixSetValues(ij_, n, row_lengths_.data(), row_numbers_.data(), columns_.data(), A.valuePtr());
    HYPRE_IJMatrixAssemble(ij_);
    HYPRE_IJMatrixGetObject(ij_, reinterpret_cast<void**>(&matrix_));
    hypre_ParCSRMatrix* par = reinterpret_cast<hypre_ParCSRMatrix*>(matrix_);
    diag_ = hypre_ParCSRMatrixDiag(par);
    offd_ = across ? hypre_ParCSRMatrixOffd(par) : nullptr;
    if (offd_ && hypre_CSRMatrixNumNonzeros(offd_) == 0) offd_ = nullptr;
    // hypre's entry k of row i holds the assembly's entry with the same (global) column: a
    // binary search in the row sorted by global column.
    const int offd_nnz = offd_ ? hypre_CSRMatrixNumNonzeros(offd_) : 0;
    if (hypre_CSRMatrixNumNonzeros(diag_) + offd_nnz != A.nonZeros())
      throw std::logic_error("amg: hypre's copy of the pressure matrix has a different number of entries");
    source_.resize(static_cast<std::size_t>(hypre_CSRMatrixNumNonzeros(diag_)));
    source_offd_.resize(static_cast<std::size_t>(offd_nnz));
    const int* hi = hypre_CSRMatrixI(diag_);
    const int* hj = hypre_CSRMatrixJ(diag_);
    const int* oi = offd_ ? hypre_CSRMatrixI(offd_) : nullptr;
    const int* oj = offd_ ? hypre_CSRMatrixJ(offd_) : nullptr;
    const HYPRE_BigInt* col_map = offd_ ? hypre_ParCSRMatrixColMapOffd(par) : nullptr;
#pragma omp parallel if (n > 10000)
    {
      std::vector<std::pair<HYPRE_BigInt, int>> row;
#pragma omp for schedule(static)
      for (int i = 0; i < n; ++i) {
        row.clear();
        for (int e = outer[i]; e < outer[i + 1]; ++e) row.emplace_back(columns_[static_cast<std::size_t>(e)], e);
        std::sort(row.begin(), row.end());
        auto entryOf = [&](HYPRE_BigInt column) {
          return std::lower_bound(row.begin(), row.end(), std::make_pair(column, -1))->second;
        };
        for (int k = hi[i]; k < hi[i + 1]; ++k)
          source_[static_cast<std::size_t>(k)] = entryOf(static_cast<HYPRE_BigInt>(first_row_) + hj[k]);
        if (offd_)
          for (int k = oi[i]; k < oi[i + 1]; ++k) source_offd_[static_cast<std::size_t>(k)] = entryOf(col_map[oj[k]]);
      }
    }

    b_ = makeVector(comm, n, ij_b_);
    x_ = makeVector(comm, n, ij_x_);
    r_ = makeVector(comm, n, ij_r_);

    // One V-cycle per application (MaxIter 1, no tolerance). hypre's defaults otherwise (2.26:
    // HMIS coarsening, extended+i interpolation truncated to 4 entries, l1-Gauss-Seidel
    // smoothing): they suit non-symmetric, M-matrix-like Poisson operators.
    HYPRE_BoomerAMGCreate(&amg_);
    HYPRE_BoomerAMGSetPrintLevel(amg_, 0);
    HYPRE_BoomerAMGSetMaxIter(amg_, 1);
    HYPRE_BoomerAMGSetTol(amg_, 0.0);
    HYPRE_BoomerAMGSetStrongThreshold(amg_, options_.amg_strong_threshold);
    if (options_.type == "bicgstab") {
      HYPRE_ParCSRBiCGSTABCreate(comm, &krylov_);
      HYPRE_ParCSRBiCGSTABSetTol(krylov_, options_.tolerance);
      HYPRE_ParCSRBiCGSTABSetMaxIter(krylov_, options_.max_iterations);
      HYPRE_ParCSRBiCGSTABSetPrecond(krylov_, HYPRE_BoomerAMGSolve, keepHierarchy, amg_);
      HYPRE_ParCSRBiCGSTABSetup(krylov_, matrix_, b_, x_);
    } else if (options_.type == "cg") {
      HYPRE_ParCSRPCGCreate(comm, &krylov_);
      HYPRE_ParCSRPCGSetTol(krylov_, options_.tolerance);
      HYPRE_ParCSRPCGSetMaxIter(krylov_, options_.max_iterations);
      HYPRE_ParCSRPCGSetTwoNorm(krylov_, 1);  // |r| / |b|, as the other solvers
      HYPRE_ParCSRPCGSetPrecond(krylov_, HYPRE_BoomerAMGSolve, keepHierarchy, amg_);
      HYPRE_ParCSRPCGSetup(krylov_, matrix_, b_, x_);
    } else {
      HYPRE_ParCSRGMRESCreate(comm, &krylov_);
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
    for (HYPRE_IJVector* v : {&ij_b_, &ij_x_, &ij_r_})
      if (*v) HYPRE_IJVectorDestroy(*v);
    if (ij_) HYPRE_IJMatrixDestroy(ij_);
    krylov_ = amg_ = nullptr;
    b_ = x_ = r_ = nullptr;
    ij_b_ = ij_x_ = ij_r_ = nullptr;
    ij_ = nullptr;
    matrix_ = nullptr;
    diag_ = offd_ = nullptr;
  }

  LinearSolverOptions options_;
  std::string name_;
  const DistributedRows* across_ = nullptr;  // during solveAcross
  MPI_Comm comm_ = MPI_COMM_NULL;            // of the built matrix
  std::int64_t first_row_ = 0;
  HYPRE_IJMatrix ij_ = nullptr;
  HYPRE_ParCSRMatrix matrix_ = nullptr;  // owned by ij_
  hypre_CSRMatrix* diag_ = nullptr;      // matrix_'s local block (all of it serially)
  hypre_CSRMatrix* offd_ = nullptr;      // across processes: the columns of other processes' rows
  HYPRE_IJVector ij_b_ = nullptr, ij_x_ = nullptr, ij_r_ = nullptr;
  HYPRE_ParVector b_ = nullptr, x_ = nullptr, r_ = nullptr;  // owned by their IJ vectors
  HYPRE_Solver amg_ = nullptr, krylov_ = nullptr;
  std::vector<int> row_lengths_;
  std::vector<HYPRE_BigInt> row_numbers_, columns_;
  std::vector<int> source_, source_offd_;  // hypre's entry k = the assembly's entry source_[k]
  Eigen::VectorXd guess_;                  // the initial guess, kept for a second attempt
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
