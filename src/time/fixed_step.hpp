#pragma once
// Shared driver of the fixed-step predictor-correctors: the step is the smallest stability
// limit at the current state, shortened to land exactly on the requested output time.
// The carried rate is F = the full right-hand side, or for the semi-implicit splitting
// (src/time/semi_implicit.cpp) its explicit part f_E, whose limits alone then set the step.
#include <algorithm>
#include <cmath>
#include <vector>

#include "vesph/core/types.hpp"
#include "vesph/time/integrator_factory.hpp"

namespace vesph {

class FixedStepIntegrator : public Integrator {
 public:
  explicit FixedStepIntegrator(const StepControl& c, RhsPart rate_part = RhsPart::full)
      : control_(c), rate_part_(rate_part) {}

  void start(OdeSystem& system, double t0, double* y) override {
    sys_ = &system;
    t_ = t0;
    y_ = y;
    n_ = system.size();
    rate_.assign(n_, 0.0);
    work_.assign(n_, 0.0);
    allocate();
    evaluate(t_, y_, rate_.data());  // F^0, also fills the stability snapshot
  }

  StepLimits limits() const override {
    return sys_ && control_.fixed_step == 0 ? stepLimits(stabilityInputs(), control_) : StepLimits{};
  }

  bool advance(double tout) override {
    while (t_ < tout) {
      double dt = control_.fixed_step > 0 ? control_.fixed_step : stepLimits(stabilityInputs(), control_).smallest();
      if (!std::isfinite(dt))
        throw InputError("integrator: no stability limit bounds the time step (no sound speed, viscosity, "
                         "motion or force); set integrator.max_step (s)");
      // Land exactly on tout; split a remainder below 1.5 dt into two equal steps so that no
      // tiny step follows a full one.
      const double rest = tout - t_;
      if (rest <= dt * (1 + 1e-12)) dt = rest;
      else if (rest < 1.5 * dt && control_.fixed_step == 0) dt = 0.5 * rest;
      step(dt);
      t_ = (rest == dt) ? tout : t_ + dt;
      last_dt_ = dt;
      ++stats_.steps;
      if (!sys_->afterStep(t_, dt, y_)) return false;
      if (sys_->resizePending()) {  // particles released or removed: a new state, F again
        // Particles only moved between processes: the rate moves with them, unless a hook
        // changed the state (the ISPH projection), whose rate is evaluated anew as below.
        const bool keeps_rates = sys_->resizeKeepsRates() && !sys_->afterStepChangesState();
        if (keeps_rates) sys_->stashRates(rate_.data());
        y_ = sys_->resizeState(t_, y_);
        n_ = sys_->size();
        rate_.assign(n_, 0.0);
        work_.assign(n_, 0.0);
        allocate();
        if (keeps_rates) sys_->takeRates(rate_.data());
        else evaluate(t_, y_, rate_.data());
      } else if (sys_->afterStepChangesState()) {
        evaluate(t_, y_, rate_.data());  // F at the projected state
      }
    }
    return true;
  }

  std::vector<double> carried() const override { return rate_; }
  void restoreCarried(const std::vector<double>& values) override {
    if (values.size() == rate_.size()) rate_ = values;
  }

  double time() const override { return t_; }
  double lastStep() const override { return last_dt_; }
  IntegratorStats stats() const override { return stats_; }

 protected:
  // Advances y_ by dt; on entry rate_ holds F(t_, y_); on exit it must hold F at the new state.
  virtual void step(double dt) = 0;
  // Sizes the integrator's own buffers for a state of n_ values (at start and after a resize).
  virtual void allocate() {}

  // The carried rate's evaluation: F, or f_E for the semi-implicit splitting.
  void evaluate(double t, const double* y, double* f) {
    if (rate_part_ == RhsPart::full) sys_->rhs(t, y, f);
    else sys_->rhsPart(rate_part_, t, y, f);
    ++stats_.rhs_evals;
  }
  // The midpoint rule (Fang eqs. 49-50) on the carried rate, from rate_ = F(t_, y_):
  // X^{n+1/2} = X^n + dt/2 F^n, X^{n+1} = X^n + dt F^{n+1/2}, then F^{n+1} (the midpoint
  // integrator's step; the semi-implicit splitting's S_E on f_E).
  void midpointStep(double dt) {
    double* y = y_;
    double* f = rate_.data();
    std::vector<double>& y0 = work_;
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < n_; ++k) {
      y0[k] = y[k];
      y[k] += 0.5 * dt * f[k];
    }
    evaluate(t_ + 0.5 * dt, y, f);
#pragma omp parallel for schedule(static) if (n_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < n_; ++k) y[k] = y0[k] + dt * f[k];
    evaluate(t_ + dt, y, f);
  }
  // The stability inputs of the carried rate's last evaluation.
  StabilitySnapshot stabilityInputs() const {
    return rate_part_ == RhsPart::full ? sys_->stability() : sys_->explicitStability();
  }

  StepControl control_;
  RhsPart rate_part_;
  OdeSystem* sys_ = nullptr;
  double* y_ = nullptr;
  std::size_t n_ = 0;
  double t_ = 0, last_dt_ = 0;
  std::vector<double> rate_, work_;
  IntegratorStats stats_;
};

}  // namespace vesph
