#pragma once
// Boundaries act on fixed particles during the right-hand side, after the state phase
// (fluid pressures known) and before the pair passes that read the boundary values.
#include <string_view>

#include "vesph/physics/effect.hpp"
#include "vesph/physics/pair_driver.hpp"

namespace vesph {

template <int D>
class Boundary {
 public:
  virtual ~Boundary() = default;
  virtual std::string_view name() const = 0;
  virtual void setup(Setup<D>& s) = 0;
  // Once the fields requested at setup are allocated (zeros), before anything runs: a boundary
  // puts its per-particle values there (moving walls: each particle's motion and reference
  // position, which then travel with it in a run across processes).
  virtual void fieldsAllocated(ParticleSet<D>& particles) {}
  // A boundary that moves fixed particles (moving walls): place sets their positions and
  // velocities at time t; the system calls it before every right-hand-side evaluation (before
  // the neighbour list's update) and before the between-step hooks, and the neighbour list
  // then watches the fixed particles' displacement as well.
  virtual bool movesFixed() const { return false; }
  virtual void place(double t, ParticleSet<D>& particles) {}
  virtual void update(const RhsContext<D>& ctx, const NeighbourList<D>& list, PairDriver<D>& driver) = 0;
  // How the fixed particles' velocities, as this boundary sets them from the fluid's
  // (v_w = prescribed + sum_f c_wf v_f), follow a uniform fluid velocity: dependence[w -
  // n_moving] = sum_f c_wf (-1 for the no-slip mirror; left 0 for a prescribed velocity). For
  // the assembled preconditioner of arkode-imex (OdeSystem::implicitVelocityOperator).
  virtual void velocityDependence(const ParticleSet<D>& particles, std::vector<double>& dependence) const {}
  // The moving set changed between steps: fixed particles moved to new indices (ParticleRemap).
  virtual void resized(const ParticleRemap& remap) {}
};

}  // namespace vesph
