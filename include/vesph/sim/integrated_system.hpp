#pragma once
// What an integrator integrates in a run (docs/architecture.md "The life of one step"): the
// OdeSystem made of the SPH system (the right-hand side, the hooks), the run's OdeState (y and
// its resize) and the run's StepObserver (diagnostics, checks, stopping). After each accepted
// step the system's hooks and effects act first, then the observer decides whether the run goes
// on; a particle-count change rearranges the particles in the system and repacks the state
// here. Nothing in the system calls back into the run: the observer is an interface that the
// run implements and hands in, and the state never leaves OdeState.
#include "vesph/sim/ode_state.hpp"
#include "vesph/sim/system.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

// The run's look at every accepted step, after the hooks: false stops the integration.
class StepObserver {
 public:
  virtual bool accepted(double t, double dt, const double* y) = 0;

 protected:
  ~StepObserver() = default;
};

template <int D>
class IntegratedSystem final : public OdeSystem {
 public:
  IntegratedSystem(SphSystem<D>& system, OdeState& state, StepObserver& observer)
      : system_(system), state_(state), observer_(observer) {}

  std::size_t size() const override { return system_.size(); }
  StateSegments segments() const override { return system_.segments(); }
  void rhs(double t, const double* y, double* ydot) override { system_.rhs(t, y, ydot); }
  StabilitySnapshot stability() const override { return system_.stability(); }
  void rhsPart(RhsPart part, double t, const double* y, double* ydot) override { system_.rhsPart(part, t, y, ydot); }
  StabilitySnapshot explicitStability() const override { return system_.explicitStability(); }
  bool implicitVelocityOperator(double t, const double* y, CsrMatrix& L) override {
    return system_.implicitVelocityOperator(t, y, L);
  }
  bool afterStep(double t, double dt, double* y) override {
    system_.afterStep(t, dt, y);
    return observer_.accepted(t, dt, y);
  }
  bool afterStepChangesState() const override { return system_.afterStepChangesState(); }
  bool mayResize() const override { return system_.mayResize(); }
  bool resizePending() const override { return system_.resizePending(); }
  const void* stateCommunicator() const override { return system_.stateCommunicator(); }
  bool resizeKeepsRates() const override { return system_.resizeKeepsRates(); }
  void stashRates(const double* rate) override { system_.stashRates(rate); }
  void takeRates(double* rate) const override { system_.takeRates(rate); }
  // The particles rearranged, the state packed at its new length; the last good state is the
  // rewritten one (same time).
  double* resizeState(double t, double* y) override {
    system_.rearrangeParticles(y);
    double* resized = state_.resize(system_.size());
    system_.pack(resized);
    state_.keepCurrentAsGood(t);
    return resized;
  }

 private:
  SphSystem<D>& system_;
  OdeState& state_;
  StepObserver& observer_;
};

}  // namespace vesph
