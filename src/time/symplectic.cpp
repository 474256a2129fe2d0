// Symplectic position Verlet (drift-kick-drift) with one right-hand-side evaluation per step:
// the rates of the previous step's midpoint evaluation are reused to predict the next midpoint
// (first-same-as-last in spirit: the last evaluation of a step supplies the first rates of the
// next). Leimkuhler & Reich (2004), "Simulating Hamiltonian Dynamics", ch. 2 (Stormer-Verlet
// in position form); Monaghan (2005), Rep. Prog. Phys. 68, 1703 (the symplectic SPH step); the
// predictor with the last midpoint rates is PySPH's predict-evaluate-correct (PECIntegrator).
// docs/theory.md §9.4 gives the equations:
//   half drift   r^{n+1/2} = r^n + dt/2 (v^n + u^{n-1/2}), u = dx/dt - v (XSPH; zero without)
//   predictor    q^{n+1/2} = q^n + dt/2 F_q^{n-1/2}        q = density, velocity, stresses
//   evaluate     F^{n+1/2} = F(r^{n+1/2}, q^{n+1/2})       the only evaluation of the step
//   kick         q^{n+1}   = q^n + dt F_q^{n+1/2}          midpoint rule
//   drift        r^{n+1}   = r^{n+1/2} + dt/2 (v^{n+1} + u^{n+1/2})
// For a force that depends on positions only the (r, v) part is exactly position Verlet, so
// symplectic and time-reversible at a fixed step. The density and the elastic stresses take
// the velocity's midpoint rule; their predicted midpoint values differ from the exact ones by
// O(dt^2) (F^{n-1/2} - F^n = O(dt)), a local O(dt^3) effect: the scheme is second order, also
// when the step changes from one step to the next (the carried rates stay O(dt) from those at
// t^n whatever the previous step was), so an adaptive step costs nothing extra.
// Linear stability for y' = z y/dt on the carried-rate pair (y, dt F): the characteristic
// polynomial is x^2 - (1 + 3z/2) x + z/2, stable for real -1 <= z < 0 (a relaxation
// dS/dt = -S/lambda needs dt <= lambda, relaxation_coefficient <= 1) and, like Heun's method,
// weakly amplifying on the imaginary axis (|x| = 1 + 2.4e-3 at |z| = 0.3): the damping of the
// artificial viscosity and density diffusion carries acoustic modes, so the CFL coefficient is
// measured, not derived (docs/performance.md "One evaluation per step").
// The carried rate (Integrator::carried) is F at the last evaluation, with its position part
// replaced by the drift rate at the step's end, v^{n+1} + u^{n+1/2}; after a hook that changes
// the state or the particle set, the base class evaluates F at the new state, whose position
// part is that rate by definition.
#include "fixed_step.hpp"

namespace vesph {
namespace {

class Symplectic final : public FixedStepIntegrator {
 public:
  using FixedStepIntegrator::FixedStepIntegrator;
  std::string name() const override { return "symplectic"; }
  int order() const override { return 2; }

 protected:
  void step(double dt) override {
    const StateSegments s = sys_->segments();
    double* y = y_;
    double* f = rate_.data();
    std::vector<double>& old = work_;  // q^n (densities, velocities, stresses) during the step
    // Half drift of the positions, predictor of everything else: all with the carried rates.
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < n_; ++k) {
      if (k >= s.position_end) old[k] = y[k];
      y[k] += 0.5 * dt * f[k];
    }
    evaluate(t_ + 0.5 * dt, y, f);  // F^{n+1/2}
    // Kick the velocities (and stresses) with the midpoint rates, then finish the drift with
    // the new velocity plus the non-velocity part of dx/dt at the midpoint (y[kv] = v^{n+1/2}
    // before the kick); that drift rate is the next step's half-drift rate.
    const std::size_t nm = n_ - s.velocity_begin, nv = s.velocity_end - s.velocity_begin;
#pragma omp parallel for schedule(static) if (nm >= kParallelMinimumValues)
    for (std::size_t k = 0; k < nm; ++k) {
      const std::size_t kv = s.velocity_begin + k;
      const double drift = k < nv ? f[s.position_begin + k] - y[kv] : 0.0;
      y[kv] = old[kv] + dt * f[kv];
      if (k < nv) {
        const std::size_t kp = s.position_begin + k;
        f[kp] = y[kv] + drift;
        y[kp] += 0.5 * dt * f[kp];
      }
    }
    // Densities: midpoint rule from rho^n.
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = s.position_end; k < s.velocity_begin; ++k) y[k] = old[k] + dt * f[k];
  }
};

}  // namespace

std::unique_ptr<Integrator> makeSymplectic(ConfigTable&, const StepControl& c, const ReferenceScales&) {
  return std::make_unique<Symplectic>(c);
}

}  // namespace vesph
