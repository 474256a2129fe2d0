#include "vesph/sim/ode_state.hpp"

#include "vesph/core/types.hpp"

namespace vesph {

double* OdeState::resize(std::size_t length) {
  y_.resize(length);
  return y_.data();
}

void OdeState::keepGood(double t, const double* y) {
  const std::size_t len = y_.size();
  last_good_.resize(len);
  double* keep = last_good_.data();
#pragma omp parallel for schedule(static) if (len >= kParallelMinimumValues)
  for (std::size_t k = 0; k < len; ++k) keep[k] = y[k];
  last_good_time_ = t;
}

void OdeState::keepCurrentAsGood(double t) {
  last_good_ = y_;
  last_good_time_ = t;
}

}  // namespace vesph
