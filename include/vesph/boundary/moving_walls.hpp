#pragma once
// Moving walls (issue 33 item 2; docs/theory.md §6.2): a wall block ([[blocks]] kind = "wall")
// with a prescribed rigid motion, a translation velocity U and/or a rotation of angular velocity
// omega about the axis through axis_point c, optionally ramped up from rest over ramp_time T:
//     f(t) = 0.5 (1 - cos(pi t / T))  (t < T),  1 after;     F(t) = int_0^t f = the motion's clock
//     c(t) = c + U F(t),   theta(t) = |omega| F(t) about e = omega / |omega| (2D: about z)
//     x_w(t) = c(t) + R(theta(t)) (x_w(0) - c)                                  (position)
//     u_w(t) = f(t) [U + omega x (x_w(t) - c(t))]                              (velocity, dx_w/dt)
//     a_w(t) = f'(t) [U + omega x r] + f(t)^2 omega x (omega x r),  r = x_w(t) - c(t)
// The wall particles are not integrated: before every right-hand-side evaluation and before the
// between-step hooks (Boundary::place, called by SphSystem with the evaluation's time) their
// positions and velocities are set from t exactly, so every integrator sees them as functions
// of time, and a resumed run continues the motion from its time (the reference positions
// x_w(0) are the blocks' lattice, rebuilt from the scene). Through the particles' velocity u_w
// enters the dummy layers' no-slip extrapolation 2 u_w - v~ (and the image walls' eq. 47), the
// continuity equation and the ISPH wall conditions; a_w enters the wall pressure (Adami eq. 27,
// field wall_acceleration, read by DummyWalls and the ISPH walls when it exists). A rotating
// block also gives its current spin Omega = f(t) omega (field wall_spin): the dummy layers then
// mirror the fluid's velocity relative to the rigid motion, whose Shepard average over the
// fluid neighbours is u_w + Omega x (x~_f - x_w), not u_w (docs/theory.md §6.2).
// Image walls (treatment = "image") may translate but not rotate (their normals are fixed).
#include <cstddef>
#include <vector>

#include "vesph/boundary/boundary.hpp"

namespace vesph {

// The [[blocks]] keys that set a wall block moving (buildMovingWalls); the scene parser refuses
// slip = "free" with any of them (a free-slip wall is at rest): one list for both.
inline constexpr const char* kWallMotionKeys[] = {"velocity", "angular_velocity", "ramp_time"};

template <int D>
struct WallMotion {
  Vec<D> velocity = Vec<D>::Zero();  // U, m/s
  // omega, rad/s: 2D the z component only (index 2 unused), 3D the vector.
  Vec<3> angular_velocity = Vec<3>::Zero();
  Vec<D> axis_point = Vec<D>::Zero();  // c, m
  double ramp_time = 0;                // T, s (0: no ramp)
  std::size_t first = 0, count = 0;    // the block's particles as offsets into the fixed ones

  bool rotates() const { return angular_velocity.squaredNorm() > 0; }
  // f(t), f'(t) and F(t) above.
  double factor(double t) const;
  double factorRate(double t) const;
  double clock(double t) const;
};

template <int D>
class MovingWalls final : public Boundary<D> {
 public:
  // reference: the positions x_w(0) of every fixed particle of the motions (fixed-particle
  // order, D per particle, indexed by the offsets of the motions).
  MovingWalls(std::vector<WallMotion<D>> motions, std::vector<double> reference, const Domain<D>& domain)
      : motions_(std::move(motions)), reference_(std::move(reference)), domain_(domain) {}
  // Components of the field wall_spin: omega_z in 2D, the vector in 3D.
  static constexpr int kSpinComponents = D == 2 ? 1 : 3;
  std::string_view name() const override { return "moving_walls"; }
  void setup(Setup<D>& s) override;
  void fieldsAllocated(ParticleSet<D>& particles) override;
  bool movesFixed() const override { return true; }
  void place(double t, ParticleSet<D>& particles) override;
  void update(const RhsContext<D>&, const NeighbourList<D>&, PairDriver<D>&) override {}

  const std::vector<WallMotion<D>>& motions() const { return motions_; }
  // The prescribed position, velocity and acceleration at time t of the particle whose
  // reference position is x0 under motion m.
  static void kinematics(const WallMotion<D>& m, double t, const Vec<D>& x0, Vec<D>& x, Vec<D>& u, Vec<D>& a);

 private:
  std::vector<WallMotion<D>> motions_;
  std::vector<double> reference_;  // until setup puts it into wall_reference
  const Domain<D>& domain_;
  Field* acceleration_ = nullptr;  // wall_acceleration, fixed particles
  Field* spin_ = nullptr;          // wall_spin f(t) omega, fixed particles (only when a block rotates)
  // Per fixed particle, so that they travel with it in a run across processes (migrations, the
  // halo): x_w(0), and the index of its motion in motions_ (-1: a wall at rest).
  Field* reference_position_ = nullptr;  // wall_reference
  Field* motion_of_ = nullptr;           // wall_motion
};

}  // namespace vesph
