#pragma once
// The hypre-based solvers behind preconditioner = "amg" (src/isph/amg_solver.cpp).
#include <memory>

#include "vesph/isph/linear_solver.hpp"

namespace vesph {

// hypre's BiCGSTAB, PCG or GMRES (options.type) preconditioned by one BoomerAMG V-cycle.
std::unique_ptr<LinearSolver> makeAmgSolver(const LinearSolverOptions& options);

}  // namespace vesph
