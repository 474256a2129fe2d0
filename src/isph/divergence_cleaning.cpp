// Divergence cleaning, the optional last stage of the ISPH projection
// (solver.divergence_cleaning; docs/theory.md §10; docs/architecture.md "ISPH projection"):
// the exact projection of the corrected velocities u onto the discretely divergence-free
// fields. With D the continuity divergence (src/isph/pressure_system.cpp), restricted to the
// unknowns and linear in the fluid velocities (walls keep theirs),
//     u <- u - dt G_a phi,   V_i (D G_a phi)_i = V_i (D u)_i / dt,
//     (G_a phi)_k = sum_j m_j (phi_k / rho_k^2 + phi_j / rho_j^2) grad_k W_kj,
// phi = 0 on free-surface and wall particles. G_a = -M^-1 D^T V (M = diag m, V = diag m/rho)
// is the adjoint of D, so V D G_a is symmetric negative semi-definite: the kinetic-energy
// orthogonal projection, which only removes energy. Its null space (checkerboards) does
// not move u; a relative diagonal shift of 1e-10 makes the matrix definite for UMFPACK/KLU.
// phi is a multiplier, not a pressure: the stored pressure stays that of the pressure solve.
// Positions are corrected with the same -dt^2/2 G_a phi.
#include <sstream>

#include "projection_parts.hpp"

namespace vesph::isph {

template <int D>
DivergenceCleaning<D>::DivergenceCleaning(const LinearSolverOptions& options) : solver_(makeLinearSolver(options)) {}

template <int D>
void DivergenceCleaning<D>::apply(StepContext<D>& sys, const ProjectionOperators<D>& ops, double t, double dt, double* y) {
  // The source is the corrected velocities' divergence at the same positions (walls at rest),
  // the gradient the adjoint of that divergence (thesis eq. 3.18 without wall pressures).
  ops.gradient.build(sys, GradientForm::symmetric, WallPressures::excluded);
  // Its own matrix and pattern record, so that the pressure solve keeps its symbolic analysis.
  const PressureUnknowns& unknowns = ops.unknowns;
  ops.system.assemble(sys, dt, LaplacianForm::exact, unknowns, ops.gradient, ops.walls, ops.divergence, nullptr,
                      system_);
  multiplier_.assign(sys.particles.size(), 0.0);
  solution_.setZero(static_cast<Eigen::Index>(unknowns.count));
  last_ = unknowns.count ? solver_->solve(system_.matrix, system_.pattern_changed, ops.system.rhs(), solution_)
                         : SolveReport{true, 0, 0.0, {}};
  if (!last_.ok) {
    std::ostringstream os;
    os << "ISPH divergence cleaning failed at t = " << t << " s (" << unknowns.count << " unknowns): " << last_.message;
    throw NumericalFailure(os.str());
  }
  for (std::size_t r = 0; r < unknowns.count; ++r)
    multiplier_[unknowns.particle_of[r]] = solution_[static_cast<Eigen::Index>(r)];
  correctVelocities(sys, ops, dt, y, multiplier_.data(), nullptr);
  iterations_total += static_cast<std::uint64_t>(last_.iterations);
  iterations_max = std::max(iterations_max, last_.iterations);
  residual_max = std::max(residual_max, last_.residual);
}

template class DivergenceCleaning<2>;
template class DivergenceCleaning<3>;

}  // namespace vesph::isph
