#pragma once
// The computational box: bounds per axis, and which axes are periodic.
// Positions along periodic axes are never wrapped in the ODE state (a jump of one period
// would wreck an error-controlled integrator's step). The particle set holds them wrapped
// into [lo, hi) (SphSystem::unpack), so separations of particle-set positions are below one
// period and the minimum image needs no rounding call in the pair loop.
#include <array>
#include <cmath>

#include "vesph/core/types.hpp"

namespace vesph {

template <int D>
struct Domain {
  Vec<D> lo = Vec<D>::Zero();
  Vec<D> hi = Vec<D>::Ones();
  std::array<bool, D> periodic{};

  double length(int a) const { return hi[a] - lo[a]; }

  // Minimum-image separation along axis a, for a separation d of two wrapped positions
  // (|d| < one period).
  double image(int a, double d) const {
    if (!periodic[a]) return d;
    const double L = hi[a] - lo[a];
    if (d > 0.5 * L) return d - L;
    if (d < -0.5 * L) return d + L;
    return d;
  }

  // Coordinate wrapped into [lo, hi) along periodic axes; unchanged otherwise.
  double wrap(int a, double x) const {
    if (!periodic[a]) return x;
    const double L = hi[a] - lo[a];
    double y = x - L * std::floor((x - lo[a]) / L);
    if (y >= hi[a]) y -= L;  // guards rounding at the upper edge
    return y;
  }

  bool insideNonPeriodic(const double* x) const {
    for (int a = 0; a < D; ++a)
      if (!periodic[a] && (x[a] < lo[a] || x[a] > hi[a])) return false;
    return true;
  }
};

}  // namespace vesph
