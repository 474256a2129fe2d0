#pragma once
// Open boundaries: an inflow buffer that feeds fluid at a prescribed velocity profile, and an
// outflow plane past which fluid particles are removed (die swell, seed thesis Ch. 4; the
// issue's "prescribed flow rate" option). A post-step hook (docs/architecture.md "The life of
// one step": hooks after each accepted step, "inflow"); the particle-count changes it asks for
// are made between steps (StepHook::collectChanges, SphSystem::rearrangeParticles).
//
// Inflow buffer ([inflow]): a box of fixed particles (kind 3, "inflow") on the lattice of the
// blocks, upstream of the inlet plane (the box face the flow direction points to). Each buffer
// particle moves with the prescribed velocity u(s) e, e the flow direction, s the coordinate
// across the box along profile_axis:
//   uniform    u = U
//   parabolic  u = 6 U eta (1 - eta), eta = (s - s_min) / (s_max - s_min)   (plane Poiseuille,
//              fully developed; U its mean over the width, the flow rate U W per unit depth)
// A circular nozzle (3D, `radius` R): the buffer's particles on rings about the box's
// cross-section centre (as a `cylinder` block along the flow axis places them: ring k at
// r_k = (k + 1/2) dr, dr = R / round(R / dx), round(2 pi r_k / dx) particles, mass rho0 times the
// ring cell's volume), one station per spacing along the flow, and
//   uniform    u = U
//   parabolic  u = 2 U (1 - r^2 / R^2)   (Hagen-Poiseuille, U its mean over the disk, the flow
//              rate U pi R^2; each ring moves at its annulus' mean of u, so that the rings
//              carry exactly that rate)
// optionally ramped up from rest over ramp_time by 0.5 (1 - cos(pi t / T)) (the positions
// advance by the exact integral of the ramped speed). The buffer is at least one kernel support
// deep, so a fluid particle at the inlet has a full support. A buffer particle that crosses the
// inlet plane is released into the fluid (a new moving particle, a new id, the buffer
// particle's position, velocity, density and fields) and the buffer particle jumps back by
// the buffer depth, so each lane keeps its lattice spacing and feeds at its own rate.
// velocity = "extrapolated" instead: each lane of the buffer (a row along the flow) carries the
// mean velocity of the fluid in its lane within two spacings downstream of the inlet (a
// zero-gradient inlet) and moves so that its leading particle stays one spacing behind the
// lane's most upstream fluid particle (attached to the fluid, never backwards); its particles
// then take the ambient pressure (that of rho0: a pressure inlet, which pins the pressure level
// that a zero-gradient velocity leaves free), for flows driven by the scene itself: the thesis' die swell, where a body force
// acts only inside the die (§4.4; effects.body_force.region_min/max) and the inlet takes in
// whatever the die flow carries.
// For the fluid the buffer is a wall with a Dirichlet velocity: its particles carry their own
// velocity into the viscous term (no Adami mirror) and the pressure and stresses are
// extrapolated from the fluid like those of dummy walls (a zero-gradient condition,
// vesph/boundary/dummy_walls.hpp).
//
// Outflow ([outflow]): the plane x . n = position (n a coordinate unit vector pointing out);
// after each step fluid particles beyond it are removed. It must lie inside the domain by at
// least one kernel support.
//
// Mass accounting: released - removed = change of the fluid particle count, in the
// diagnostics (columns released, removed, fluid_particles) and summary.json (flow{...}).
#include <array>
#include <memory>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/physics/step_hook.hpp"

namespace vesph {

template <int D>
class InflowOutflow final : public StepHook<D> {
 public:
  // Reads [inflow] and [outflow]; returns nullptr when the scene has neither. Appends the
  // buffer particles to the set as fixed particles (after every other particle).
  static std::unique_ptr<InflowOutflow> fromConfig(ConfigTable& root, ParticleSet<D>& particles,
                                                   const Domain<D>& domain, double spacing, double rest_density,
                                                   double support, std::uint64_t& next_id);

  std::string_view name() const override { return "inflow_outflow"; }
  void apply(StepContext<D>& system, double t, double dt, double* y) override;
  bool changesParticles() const override { return true; }
  bool pendingChanges() const override { return !release_.empty() || !remove_.empty(); }
  void collectChanges(const StepContext<D>& system, ParticleChanges& out) override;
  void resized(StepContext<D>& system, const ParticleRemap& remap) override;
  std::vector<std::string> diagnosticsColumns() const override { return {"released", "removed", "fluid_particles"}; }
  void diagnostics(std::vector<double>& values) const override;
  void summarize(nlohmann::json& summary) const override;
  std::string describe() const override;
  // Checkpoints: the release/removal totals and the lanes' last extrapolated speeds (a lane
  // with no fluid at the inlet keeps its last speed). The buffer particles' positions are in
  // the particle set, which the checkpoint keeps whole for such scenes.
  void saveCarried(NamedArrays& out) const override;
  void restoreCarried(const ArrayLookup& find) override;
  // Runs across processes: the buffer is the owned fixed particles of kind inflow, each
  // prescribed speed travelling with its particle as the fixed-range field "inflow_speed", each
  // lane (extrapolated velocity) found from the position; a lane's means and extremes are
  // reduced over the processes.
  bool distributable() const override { return true; }
  void distributing(ParticleSet<D>& whole) override;
  void redistributed(StepContext<D>& system) override;

  bool extrapolatedVelocity() const { return extrapolated_; }
  bool hasBuffer() const { return !buffer_.empty(); }
  // The inflow's direction e (a signed coordinate unit vector).
  Vec<D> flowDirection() const {
    Vec<D> e = Vec<D>::Zero();
    e[axis_] = sign_;
    return e;
  }
  // The largest prescribed buffer speed (1.5 U for the parabola, 2 U in a circular nozzle, U
  // uniform), m/s; 0 without
  // a prescribed inflow.
  double prescribedPeakSpeed() const {
    if (buffer_.empty() || extrapolated_) return 0.0;
    if (profile_ != "parabolic") return mean_velocity_;
    return nozzle_radius_ > 0 ? 2.0 * mean_velocity_ : 1.5 * mean_velocity_;
  }
  // The buffer's speed factor at time t (the ramp) and its integral from 0 to t.
  double rampFactor(double t) const;
  double rampIntegral(double t) const;

 private:
  // The buffer particles of fromConfig: the box's lattice (its profile across profile_axis), or
  // the circular nozzle's rings (radius nozzle_radius_).
  // One buffer particle at x moving at speed along the flow (ramped), of the given mass.
  void addBufferParticle(ParticleSet<D>& p, const Vec<D>& x, double speed, double rho0, double mass,
                         std::uint64_t& next_id);
  void placeBox(ParticleSet<D>& p, ConfigTable& in, const Vec<D>& lo, const Vec<D>& hi, const std::array<long, D>& n,
                double dx, double rho0, std::uint64_t& next_id);
  void placeNozzle(ParticleSet<D>& p, const Vec<D>& lo, const Vec<D>& hi, const std::array<long, D>& n, double dx,
                   double rho0, std::uint64_t& next_id);
  // Inflow.
  std::vector<std::size_t> buffer_;  // buffer particles as offsets into the fixed particles
  std::vector<double> speed_;        // their full prescribed speed u(s), m/s
  int axis_ = 0;                     // flow direction e = sign e_axis
  double sign_ = 1;
  double inlet_ = 0;                 // the inlet plane x[axis] = inlet
  double depth_ = 0;                 // buffer depth along the flow, m
  double mean_velocity_ = 0, ramp_time_ = 0;
  std::string profile_;
  // velocity = "extrapolated": each lane (a row of the buffer along the flow) moves with the
  // mean velocity of the fluid just downstream of the inlet in that lane.
  bool extrapolated_ = false;
  double spacing_ = 0;
  Vec<D> lo_ = Vec<D>::Zero();
  std::array<long, D> counts_{};
  double nozzle_radius_ = 0;  // m; 0: the whole box (no circular nozzle)
  std::vector<long> lane_;  // per buffer particle
  std::vector<double> lane_speed_, lane_sum_, lane_trail_, lane_lead_, lane_shift_;
  std::vector<long> lane_count_;
  double support_ = 0;
  long laneOf(const Vec<D>& x) const;
  void followFluid(ParticleSet<D>& p, const double* y, std::size_t n_moving);
  // Outflow.
  bool outflow_ = false;
  int out_axis_ = 0;
  double out_sign_ = 1, out_position_ = 0;
  // This step's changes and the totals.
  std::vector<Index> release_, remove_;
  std::vector<std::size_t> released_offsets_;  // buffer offsets released this step
  std::uint64_t released_ = 0, removed_ = 0;
  std::size_t fluid_count_ = 0;
};

}  // namespace vesph
