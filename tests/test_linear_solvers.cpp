// The Krylov solvers with each preconditioner (include/vesph/isph/linear_solver.hpp): cg, gmres
// and the hypre BoomerAMG preconditioner solve known systems, keep their hierarchy across
// solves, and report a singular or non-converging system instead of returning a bad solution.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "vesph/isph/linear_solver.hpp"

using namespace vesph;

namespace {

// The 5-point Laplacian on an m x m grid with Dirichlet boundaries (symmetric positive
// definite), plus a first-derivative term of strength `convection` (non-symmetric).
SparseRowMatrix gridOperator(int m, double convection) {
  std::vector<Eigen::Triplet<double>> t;
  auto id = [m](int i, int j) { return i * m + j; };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      t.emplace_back(id(i, j), id(i, j), 4.0);
      if (i > 0) t.emplace_back(id(i, j), id(i - 1, j), -1.0 - convection);
      if (i < m - 1) t.emplace_back(id(i, j), id(i + 1, j), -1.0 + convection);
      if (j > 0) t.emplace_back(id(i, j), id(i, j - 1), -1.0);
      if (j < m - 1) t.emplace_back(id(i, j), id(i, j + 1), -1.0);
    }
  SparseRowMatrix A(m * m, m * m);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

Eigen::VectorXd knownSolution(int n) {
  Eigen::VectorXd x(n);
  for (int k = 0; k < n; ++k) x[k] = std::sin(0.1 * k) + 0.01 * k;
  return x;
}

}  // namespace

TEST_CASE("linear solvers: bicgstab, cg and gmres with diagonal, ilut and amg preconditioners") {
  const int m = 40, n = m * m;
  const Eigen::VectorXd exact = knownSolution(n);
  for (const std::string type : {"bicgstab", "cg", "gmres"})
    for (const std::string pc : {"diagonal", "ilut", "amg"}) {
      CAPTURE(type);
      CAPTURE(pc);
      // CG needs a symmetric matrix; the others get the non-symmetric one.
      const SparseRowMatrix A = gridOperator(m, type == "cg" ? 0.0 : 0.3);
      const Eigen::VectorXd b = A * exact;
      LinearSolverOptions o;
      o.type = type;
      o.preconditioner = pc;
      o.tolerance = 1e-10;
      o.max_iterations = 5000;
      o.gmres_restart = 50;
      auto solver = makeLinearSolver(o);
      CHECK(solver->name() == type + "+" + pc);
      Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
      const SolveReport r = solver->solve(A, true, b, x);
      REQUIRE_MESSAGE(r.ok, r.message);
      CHECK(r.residual < 1e-9);
      CHECK((x - exact).norm() / exact.norm() < 1e-7);
      CHECK(r.iterations >= 1);
      if (pc == "amg") CHECK(r.iterations < 20);  // multigrid: a few iterations
      // Warm-started from the solution: no more work than from zero (GMRES tests the
      // preconditioned residual, so it may take a few iterations to the true one).
      const SolveReport again = solver->solve(A, false, b, x);
      REQUIRE_MESSAGE(again.ok, again.message);
      CHECK(again.iterations <= r.iterations);
    }
}

TEST_CASE("linear solvers: amg keeps its hierarchy while the pattern holds and rebuilds it when it changes") {
  const int m = 30, n = m * m;
  const Eigen::VectorXd exact = knownSolution(n);
  LinearSolverOptions o;
  o.type = "bicgstab";
  o.preconditioner = "amg";
  o.tolerance = 1e-10;
  o.amg_setup_interval = 3;
  auto solver = makeLinearSolver(o);
  // The values change from solve to solve with the pattern fixed (the hierarchy of the first
  // matrix preconditions the next two), then the size changes (a new pattern).
  for (int step = 0; step < 5; ++step) {
    CAPTURE(step);
    const int size = step < 4 ? m : m + 3;
    SparseRowMatrix A = gridOperator(size, 0.05 * step);
    A *= 1.0 + 0.5 * step;
    const Eigen::VectorXd want = step < 4 ? exact : knownSolution(size * size);
    const Eigen::VectorXd b = A * want;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(size * size);
    const SolveReport r = solver->solve(A, step == 0 || step == 4, b, x);
    REQUIRE_MESSAGE(r.ok, r.message);
    CHECK((x - want).norm() / want.norm() < 1e-7);
    CHECK(r.iterations < 30);
  }
  // An equation with no neighbours and nothing on its right side (a detached particle) is
  // p = 0, and the rest is solved.
  SparseRowMatrix A = gridOperator(m, 0.0);
  for (SparseRowMatrix::InnerIterator it(A, 7); it; ++it) it.valueRef() = 0.0;
  Eigen::VectorXd want = exact;
  want[7] = 0.0;
  Eigen::VectorXd b = A * want;
  b[7] = 0.0;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  const SolveReport r = solver->solve(A, true, b, x);
  REQUIRE_MESSAGE(r.ok, r.message);
  CHECK(std::abs(x[7]) < 1e-12);
}

TEST_CASE("linear solvers: a singular or non-converging system is reported with a clear message") {
  const int m = 20, n = m * m;
  for (const std::string type : {"bicgstab", "cg", "gmres"})
    for (const std::string pc : {"diagonal", "ilut", "amg"}) {
      CAPTURE(type);
      CAPTURE(pc);
      LinearSolverOptions o;
      o.type = type;
      o.preconditioner = pc;
      // Too few iterations for the tolerance.
      o.tolerance = 1e-14;
      o.max_iterations = 1;
      const SparseRowMatrix A = gridOperator(m, type == "cg" ? 0.0 : 0.3);
      Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
      const SolveReport r = makeLinearSolver(o)->solve(A, true, Eigen::VectorXd::Ones(n), x);
      CHECK_FALSE(r.ok);
      CHECK(r.message.find("no convergence") != std::string::npos);
      CHECK(r.message.find(type + "+" + pc) == 0);
    }
  // A singular matrix with a right-hand side outside its range: the pure-Neumann Laplacian (a
  // closed fluid with no free surface and no pinned pressure) and a net source. No solver may
  // return a "solution".
  std::vector<Eigen::Triplet<double>> t;
  auto id = [m](int i, int j) { return i * m + j; };
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) {
      int neighbours = 0;
      for (auto [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int a = i + di, c = j + dj;
        if (a < 0 || a >= m || c < 0 || c >= m) continue;
        t.emplace_back(id(i, j), id(a, c), -1.0);
        ++neighbours;
      }
      t.emplace_back(id(i, j), id(i, j), neighbours);
    }
  SparseRowMatrix neumann(n, n);
  neumann.setFromTriplets(t.begin(), t.end());
  for (const std::string type : {"bicgstab", "gmres", "umfpack"})
    for (const std::string pc : {"diagonal", "amg"}) {
      if (type == "umfpack" && pc == "amg") continue;
      CAPTURE(type);
      CAPTURE(pc);
      LinearSolverOptions o;
      o.type = type;
      o.preconditioner = pc;
      o.max_iterations = 500;
      Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
      const SolveReport r = makeLinearSolver(o)->solve(neumann, true, Eigen::VectorXd::Ones(n), x);
      CHECK_FALSE(r.ok);
      CHECK_FALSE(r.message.empty());
    }
  // A zero diagonal with a non-zero right side (an equation without its own unknown).
  SparseRowMatrix A = gridOperator(m, 0.0);
  A.coeffRef(5, 5) = 0.0;
  LinearSolverOptions o;
  o.type = "bicgstab";
  o.preconditioner = "amg";
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  const SolveReport r = makeLinearSolver(o)->solve(A, true, Eigen::VectorXd::Ones(n), x);
  CHECK_FALSE(r.ok);
  CHECK(r.message.find("singular") != std::string::npos);
}

// Open MPI, started as a singleton, forks a daemon (orted) that inherits the process's open
// files: the output file's HDF5 lock then outlives vesph, and a `--resume` started at once
// finds the file locked (the failure seen in cli.resume under load). The AMG solver starts MPI
// in isolated singleton mode: after a solve, this process has no child.
TEST_CASE("linear solvers: starting MPI for amg forks no daemon") {
  const int m = 10, n = m * m;
  LinearSolverOptions o;
  o.type = "cg";
  o.preconditioner = "amg";
  o.tolerance = 1e-10;
  auto solver = makeLinearSolver(o);
  const SparseRowMatrix A = gridOperator(m, 0.0);
  const Eigen::VectorXd b = A * knownSolution(n);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  REQUIRE(solver->solve(A, true, b, x).ok);
  std::string children;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream in(task.path() / "children");
    std::string pids;
    std::getline(in, pids);
    children += pids;
  }
  CHECK_MESSAGE(children.empty(), "child processes: " << children);
}
