#pragma once
// The run's look at every accepted step (docs/architecture.md "The life of one step"): one
// diagnostics row (kinetic energy, mass, fastest particle, largest density deviation, the hooks'
// columns) and the checks that stop a run as a numerical failure ([checks]: a non-finite value,
// the density deviation, the speed guard, a fluid particle outside the domain).
#include <string>
#include <vector>

#include "vesph/io/output.hpp"
#include "vesph/sim/system.hpp"

namespace vesph {

template <int D>
class StepChecks {
 public:
  double rest_density = 1;
  double max_density_deviation = 0.5;  // checks.max_density_deviation, relative
  double max_speed = 0;                // checks.max_speed, m/s
  bool removes_leaving = false;        // checks.leave_domain = "remove": leaving is no failure

  DiagnosticsRow diagnostics(const SphSystem<D>& system, double t, double dt, const double* y);
  // Why the state y fails the checks; empty when it passes.
  std::string failure(const SphSystem<D>& system, const DiagnosticsRow& row, const double* y) const;
  // The hooks' diagnostics columns, in hook order.
  static std::vector<std::string> hookColumns(const SphSystem<D>& system);

 private:
  // The checks of this process's particles.
  std::string localFailure(const SphSystem<D>& system, const DiagnosticsRow& row, const double* y) const;
  std::vector<double> hook_values_;
};

}  // namespace vesph
