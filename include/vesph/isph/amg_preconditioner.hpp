#pragma once
// One BoomerAMG V-cycle as a preconditioner for solvers outside hypre (the implicit stage
// solves of arkode-imex, src/time/arkode_imex.cpp); src/isph/amg_solver.cpp, with hypre's
// pressure solvers. MPI and hypre start at the first setUp.
#include <memory>

namespace vesph {

struct CsrMatrix;

class AmgPreconditioner {
 public:
  AmgPreconditioner();
  ~AmgPreconditioner();
  AmgPreconditioner(const AmgPreconditioner&) = delete;
  AmgPreconditioner& operator=(const AmgPreconditioner&) = delete;
  // A new hierarchy for the matrix A (square; repeated columns in a row add up).
  void setUp(const CsrMatrix& A);
  // z = M^-1 r by one V-cycle from zero (r and z of A's size; they may not alias).
  void apply(const double* r, double* z);
  int size() const;

 private:
  struct Hypre;
  std::unique_ptr<Hypre> hypre_;
};

}  // namespace vesph
