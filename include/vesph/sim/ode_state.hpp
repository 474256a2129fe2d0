#pragma once
// The ODE state of a run (docs/architecture.md "The life of one step"): the vector y the
// integrator works on (SUNDIALS wraps it without copies) and the last good copy, the state of
// the last step that passed the run's checks, written as the last frame when a later step
// fails. The one owner of both: a particle-count change between steps resizes y here
// (IntegratedSystem::resizeState), and the last good copy follows it.
#include <cstddef>
#include <vector>

namespace vesph {

class OdeState {
 public:
  std::vector<double>& values() { return y_; }
  const std::vector<double>& values() const { return y_; }
  double* data() { return y_.data(); }
  std::size_t size() const { return y_.size(); }

  // y at a new length (its values to be packed by the caller); returns its buffer.
  double* resize(std::size_t length);
  // The last good state: (t, y) when a step has passed the checks (y the integrator's buffer,
  // which is this state's), or the state as it is now (the start, a particle-count change).
  void keepGood(double t, const double* y);
  void keepCurrentAsGood(double t);
  // Back to the last good state (after a failed step).
  void restoreGood() { y_ = last_good_; }
  double goodTime() const { return last_good_time_; }

 private:
  std::vector<double> y_, last_good_;
  double last_good_time_ = 0;
};

}  // namespace vesph
