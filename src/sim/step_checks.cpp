#include "vesph/sim/step_checks.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace vesph {

template <int D>
DiagnosticsRow StepChecks<D>::diagnostics(const SphSystem<D>& system, double t, double dt, const double* y) {
  const ParticleSet<D>& p = system.particles;
  const std::size_t n = p.ownedMoving();
  const double* rho = y + n * D;
  const double* v = y + n * (D + 1);
  double ke = 0, mass = 0, vmax2 = 0, dev = 0;
  const double rho0 = rest_density;
#pragma omp parallel for reduction(+ : ke, mass) reduction(max : vmax2, dev) schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    double v2 = 0;
    for (int a = 0; a < D; ++a) v2 += v[D * i + a] * v[D * i + a];
    ke += 0.5 * p.mass[i] * v2;
    mass += p.mass[i];
    vmax2 = std::max(vmax2, v2);
    dev = std::max(dev, std::abs(rho[i] / rho0 - 1.0));
  }
  if (system.distribution) {  // the row of the whole run, the same on every process
    ke = system.distribution->sum(ke);
    mass = system.distribution->sum(mass);
    vmax2 = system.distribution->max(vmax2);
    dev = system.distribution->max(dev);
  }
  DiagnosticsRow row{t, dt, ke, mass, std::sqrt(vmax2), dev, {}};
  std::size_t k = 0;
  for (const auto& hk : system.hooks) {
    hook_values_.clear();
    hk->diagnostics(hook_values_);
    for (double v : hook_values_)
      if (k < kMaxExtraDiagnostics) row.extra[k++] = v;
  }
  return row;
}

template <int D>
std::string StepChecks<D>::failure(const SphSystem<D>& system, const DiagnosticsRow& row, const double* y) const {
  const std::string local = localFailure(system, row, y);
  // A distributed run stops on every process when one finds a failure, with its message.
  return system.distribution ? system.distribution->firstMessage(local) : local;
}

template <int D>
std::string StepChecks<D>::localFailure(const SphSystem<D>& system, const DiagnosticsRow& row, const double* y) const {
  std::ostringstream os;
  const std::size_t n = system.particles.ownedMoving();
  if (!std::isfinite(row.kinetic_energy) || !std::isfinite(row.max_density_deviation)) {
    for (std::size_t k = 0; k < n * (2 * D + 1); ++k)
      if (!std::isfinite(y[k])) {
        const std::size_t i = k < n * D ? k / D : k < n * (D + 1) ? k - n * D : (k - n * (D + 1)) / D;
        const char* field = k < n * D ? "position" : k < n * (D + 1) ? "density" : "velocity";
        os << "non-finite " << field << " of particle id " << system.particles.id[i] << " at t = " << row.time << " s";
        return os.str();
      }
  }
  // Evolving fields (elastic stresses) are not in the diagnostics: scan them (this also names
  // the cause when the diagnostics are non-finite but positions, densities, velocities are not).
  const std::size_t total = system.size();
  for (std::size_t k = n * (2 * D + 1); k < total; ++k)
    if (!std::isfinite(y[k])) {
      os << "non-finite evolving field (elastic stress) at t = " << row.time << " s";
      return os.str();
    }
  if (row.max_density_deviation > max_density_deviation) {
    os << "density deviates from the rest density by " << row.max_density_deviation * 100
       << " % (> checks.max_density_deviation = " << max_density_deviation * 100 << " %) at t = " << row.time << " s";
    return os.str();
  }
  if (row.max_speed > max_speed) {
    os << "a particle moves at " << row.max_speed << " m/s, faster than checks.max_speed = " << max_speed
       << " m/s (by default the sound speed; for ISPH 1000 times the flow speed scale) at t = " << row.time << " s";
    return os.str();
  }
  for (std::size_t i = 0; i < n && !removes_leaving; ++i)
    if (!system.domain.insideNonPeriodic(y + D * i)) {
      os << "fluid particle id " << system.particles.id[i] << " left the domain at t = " << row.time << " s";
      return os.str();
    }
  return {};
}

template <int D>
std::vector<std::string> StepChecks<D>::hookColumns(const SphSystem<D>& system) {
  std::vector<std::string> cols;
  for (const auto& hk : system.hooks)
    for (const std::string& c : hk->diagnosticsColumns()) cols.push_back(c);
  if (cols.size() > kMaxExtraDiagnostics) throw std::logic_error("too many diagnostics columns from hooks");
  return cols;
}

template class StepChecks<2>;
template class StepChecks<3>;

}  // namespace vesph
