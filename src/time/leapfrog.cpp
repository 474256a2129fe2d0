// Leapfrog predictor-corrector of the thesis, eq. (3.39) ff. (Fig. 3-2):
//   predictor   r^{n+1/2} = r^n + dt/2 v^n,  rho^{n+1/2} = rho^n + dt/2 k^n
//   velocity    v^{n+1}   = v^n + dt f^{n+1/2}
//   corrector   r^{n+1}   = r^{n+1/2} + dt/2 v^{n+1},  rho^{n+1} = rho^{n+1/2} + dt/2 k^{n+1}
// The thesis evaluates f^{n+1/2} with the velocity v^n; here the velocity is predicted to the
// half step as well (v^{n+1/2} = v^n + dt/2 f^n, f^n from the previous corrector evaluation),
// which makes the viscous and velocity-dependent forces second order too. The evolving fields
// after the velocities (elastic stresses, whose rates depend on themselves) take the
// velocity's midpoint update: S^{n+1} = S^n + dt F_S^{n+1/2}. The density follows the
// trapezoidal rule above. k^{n+1} is evaluated at (r^{n+1}, rho^{n+1/2}, v^{n+1}): the continuity
// equation (Fang eq. 26) does not depend on density, so it is exact there; the force f^{n+1}
// from that evaluation (pressure at rho^{n+1/2}) only predicts the next half-step velocity,
// an O(dt^2) local effect that keeps the scheme second order.
// Two right-hand-side evaluations per step.
#include "fixed_step.hpp"

namespace vesph {
namespace {

class Leapfrog final : public FixedStepIntegrator {
 public:
  using FixedStepIntegrator::FixedStepIntegrator;
  std::string name() const override { return "leapfrog"; }
  int order() const override { return 2; }

 protected:
  void step(double dt) override {
    const StateSegments s = sys_->segments();
    double* y = y_;
    double* f = rate_.data();
    std::vector<double>& old = work_;  // holds v^n (and S^n) during the step
    // Predictor: everything to the half step.
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < n_; ++k) {
      if (k >= s.velocity_begin) old[k] = y[k];
      y[k] += 0.5 * dt * f[k];
    }
    evaluate(t_ + 0.5 * dt, y, f);  // f^{n+1/2}
    // Velocities and evolving fields: full step from the old values with f^{n+1/2};
    // positions: corrector with v^{n+1}, plus the part of dx/dt that is not v (XSPH,
    // src/physics/xsph.cpp) as evaluated at the half step: dx/dt - v there. Without such an
    // effect dx/dt is a copy of v and that part is exactly zero.
    const std::size_t nm = n_ - s.velocity_begin, nv = s.velocity_end - s.velocity_begin;
#pragma omp parallel for schedule(static) if (nm >= kParallelMinimumValues)
    for (std::size_t k = 0; k < nm; ++k) {
      const std::size_t kv = s.velocity_begin + k;
      const double drift = k < nv ? f[s.position_begin + k] - y[kv] : 0.0;  // y[kv] = v^{n+1/2}
      y[kv] = old[kv] + dt * f[kv];
      if (k < nv) y[s.position_begin + k] += 0.5 * dt * (y[kv] + drift);
    }
    // Density: keep rho^{n+1/2}, evaluate k^{n+1}, then correct.
    evaluate(t_ + dt, y, f);
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = s.position_end; k < s.velocity_begin; ++k) y[k] += 0.5 * dt * f[k];
  }
};

// Midpoint predictor-corrector of Fang et al. (2006), eqs. (49)-(50):
//   X^{n+1/2} = X^n + dt/2 F^n,   X^{n+1} = X^n + dt F^{n+1/2}
// Two right-hand-side evaluations per step (F^{n+1} is the next step's F^n).
class Midpoint final : public FixedStepIntegrator {
 public:
  using FixedStepIntegrator::FixedStepIntegrator;
  std::string name() const override { return "midpoint"; }
  int order() const override { return 2; }

 protected:
  void step(double dt) override { midpointStep(dt); }
};

}  // namespace

std::unique_ptr<Integrator> makeLeapfrog(ConfigTable&, const StepControl& c, const ReferenceScales&) {
  return std::make_unique<Leapfrog>(c);
}
std::unique_ptr<Integrator> makeMidpoint(ConfigTable&, const StepControl& c, const ReferenceScales&) {
  return std::make_unique<Midpoint>(c);
}

}  // namespace vesph
