#pragma once
// Gauges (docs/user-guide.md "Gauges"; docs/theory.md "Gauges"): quantities measured at every
// output time from the particle set, written to /gauges/<name> of the output:
//  - point:     pressure, velocity and density at a point, SPH-interpolated with the kernel-sum
//               (Shepard) normalisation f(x) = sum_j V_j W(x - x_j) f_j / sum_j V_j W(x - x_j),
//               V_j = m_j / rho_j over the fluid particles; the kernel sum itself is written
//               too (about 1 inside the fluid, under 0.5 outside it);
//  - elevation: the free-surface height on the vertical line (the last axis) through a foot
//               point: going up from the foot, the first height where the kernel sum falls
//               below 0.5 (the surface of a half-filled support) after reaching it within one
//               kernel support of the foot (NaN otherwise: a dry foot);
//  - front:     the largest coordinate of any fluid particle along an axis (a surge front).
// Evaluated from the frame's particle set, they need nothing carried between steps: a resumed
// run keeps the rows up to its checkpoint and writes the later ones with its frames.
#include <string>
#include <vector>

#include "vesph/core/distribution.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/particles.hpp"
#include "vesph/io/config.hpp"
#include "vesph/io/output.hpp"

namespace vesph {

template <int D>
class Gauges {
 public:
  // Reads [[gauges]] (none: no gauge); InputError naming the key for a bad one.
  void read(ConfigTable& root, const Domain<D>& domain, double spacing);
  bool empty() const { return gauges_.empty(); }
  // The series the output file holds: name, type, position and columns.
  std::vector<GaugeSeries> series() const;
  // One row per gauge at time t (time first), from the particles' positions, velocities,
  // densities, masses and the "pressure" field (NaN where the scene has none). In a run across
  // processes (`distribution`), from every process's owned particles (each its sums, reduced),
  // the same rows on every process; collective then.
  std::vector<std::vector<double>> evaluate(double t, const ParticleSet<D>& p, const Kernel& kernel,
                                            const Domain<D>& domain,
                                            ParticleDistribution<D>* distribution = nullptr) const;

 private:
  enum class Type { point, elevation, front };
  struct Gauge {
    std::string name;
    Type type;
    Vec<D> position = Vec<D>::Zero();
    int axis = 0;  // front: the axis along which the front advances
  };
  void point(const Gauge& g, const ParticleSet<D>& p, const Kernel& k, const Domain<D>& dom,
             ParticleDistribution<D>* distribution, std::vector<double>& row) const;
  double elevation(const Gauge& g, const ParticleSet<D>& p, const Kernel& k, const Domain<D>& dom,
                   ParticleDistribution<D>* distribution) const;

  std::vector<Gauge> gauges_;
  double spacing_ = 0, top_ = 0;  // top_: the domain's upper bound along the vertical axis
};

}  // namespace vesph
