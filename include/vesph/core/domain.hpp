#pragma once
// The computational box: bounds per axis, and which axes are periodic.
// Positions along periodic axes are never wrapped in the ODE state (a jump of one period
// would wreck an error-controlled integrator's step); distances use the minimum image and
// the output writes wrapped positions.
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

  // Minimum-image separation along axis a.
  double image(int a, double d) const {
    if (!periodic[a]) return d;
    const double L = hi[a] - lo[a];
    return d - L * std::nearbyint(d / L);
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
