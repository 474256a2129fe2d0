#include "vesph/boundary/moving_walls.hpp"
#include "vesph/boundary/registry.hpp"

#include <cmath>
#include <algorithm>
#include <numbers>
#include <stdexcept>

#include "vesph/core/types.hpp"

namespace vesph {
namespace {
Vec<3> cross(const Vec<3>& a, const Vec<3>& b) {
  return Vec<3>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}
}  // namespace

// The ramp 0.5 (1 - cos(pi t / T)) of the inflow buffer (include/vesph/boundary/inflow_outflow.hpp),
// its rate and its integral, the motion's clock.
template <int D>
double WallMotion<D>::factor(double t) const {
  if (ramp_time <= 0 || t >= ramp_time) return 1.0;
  if (t <= 0) return 0.0;
  return 0.5 * (1.0 - std::cos(std::numbers::pi * t / ramp_time));
}

template <int D>
double WallMotion<D>::factorRate(double t) const {
  if (ramp_time <= 0 || t >= ramp_time || t <= 0) return 0.0;
  return 0.5 * std::numbers::pi / ramp_time * std::sin(std::numbers::pi * t / ramp_time);
}

template <int D>
double WallMotion<D>::clock(double t) const {
  if (ramp_time <= 0) return t;
  if (t <= 0) return 0.0;
  if (t >= ramp_time) return t - 0.5 * ramp_time;
  return 0.5 * (t - ramp_time / std::numbers::pi * std::sin(std::numbers::pi * t / ramp_time));
}

template <int D>
void MovingWalls<D>::kinematics(const WallMotion<D>& m, double t, const Vec<D>& x0, Vec<D>& x, Vec<D>& u, Vec<D>& a) {
  const double f = m.factor(t), fdot = m.factorRate(t), F = m.clock(t);
  const Vec<D> centre = m.axis_point + F * m.velocity;
  Vec<D> r = x0 - m.axis_point;  // rotated below
  Vec<D> w_r = Vec<D>::Zero(), w_w_r = Vec<D>::Zero();  // omega x r, omega x (omega x r)
  if (m.rotates()) {
    if constexpr (D == 2) {
      const double w = m.angular_velocity[2], theta = w * F;
      const double c = std::cos(theta), s = std::sin(theta);
      r = Vec<D>(c * r[0] - s * r[1], s * r[0] + c * r[1]);
      w_r = Vec<D>(-w * r[1], w * r[0]);
      w_w_r = -w * w * r;
    } else {
      const Vec<3>& w = m.angular_velocity;
      const double speed = w.norm(), theta = speed * F;
      const Vec<3> e = w / speed;
      // Rodrigues: R r = r cos + (e x r) sin + e (e . r)(1 - cos)
      const double c = std::cos(theta), s = std::sin(theta);
      r = r * c + cross(e, r) * s + e * (e.dot(r) * (1.0 - c));
      w_r = cross(w, r);
      w_w_r = cross(w, w_r);
    }
  }
  x = centre + r;
  u = f * (m.velocity + w_r);
  a = fdot * (m.velocity + w_r) + f * f * w_w_r;
}

template <int D>
void MovingWalls<D>::setup(Setup<D>& s) {
  acceleration_ = &s.particles.fields.require("wall_acceleration", D, Field::Range::fixed);
  for (const WallMotion<D>& m : motions_)
    if (m.rotates()) spin_ = &s.particles.fields.require("wall_spin", kSpinComponents, Field::Range::fixed);
  // The particles' motions and reference positions as fields: set once, never refreshed (the
  // ghosts get them with the halo).
  reference_position_ = &s.particles.fields.require("wall_reference", D, Field::Range::fixed);
  motion_of_ = &s.particles.fields.require("wall_motion", 1, Field::Range::fixed);
  reference_position_->refreshed_in_halo = motion_of_->refreshed_in_halo = false;
}

template <int D>
void MovingWalls<D>::fieldsAllocated(ParticleSet<D>&) {
  if (reference_.size() != reference_position_->data.size())
    throw std::logic_error("moving walls: the reference positions do not cover the fixed particles");
  reference_position_->data = std::move(reference_);
  reference_.clear();
  std::fill(motion_of_->data.begin(), motion_of_->data.end(), -1.0);
  for (std::size_t m = 0; m < motions_.size(); ++m)
    for (std::size_t k = motions_[m].first; k < motions_[m].first + motions_[m].count; ++k)
      motion_of_->data[k] = static_cast<double>(m);
}

template <int D>
void MovingWalls<D>::place(double t, ParticleSet<D>& p) {
  // Every fixed particle the set holds (a distributed run's ghosts too: they are placed here
  // as their owners are, at the same time).
  const std::size_t n0 = p.n_moving, n_fixed = p.nFixed();
  double* acc = acceleration_->data.data();
  double* spin = spin_ ? spin_->data.data() : nullptr;
  const double* reference = reference_position_->data.data();
  const double* motion_of = motion_of_->data.data();
#pragma omp parallel for schedule(static) if (n_fixed >= kParallelMinimum)
  for (std::size_t k = 0; k < n_fixed; ++k) {
    if (motion_of[k] < 0) continue;
    const WallMotion<D>& m = motions_[static_cast<std::size_t>(motion_of[k])];
    if (spin) {
      const double f = m.factor(t);
      for (int c = 0; c < kSpinComponents; ++c) spin[kSpinComponents * k + c] = f * m.angular_velocity[D == 2 ? 2 : c];
    }
    Vec<D> x0, x, u, a;
    for (int c = 0; c < D; ++c) x0[c] = reference[D * k + c];
    kinematics(m, t, x0, x, u, a);
    const std::size_t w = n0 + k;
    for (int c = 0; c < D; ++c) {
      p.position[D * w + c] = domain_.wrap(c, x[c]);
      p.velocity[D * w + c] = u[c];
      acc[D * k + c] = a[c];
    }
  }
}

template struct WallMotion<2>;
template struct WallMotion<3>;
template class MovingWalls<2>;
template class MovingWalls<3>;

namespace {
constexpr const char* kMotionKeys[] = {"angular_velocity", "axis_point", "ramp_time"};

}  // namespace

// The wall blocks' motions ([[blocks]] kind = "wall": velocity, angular_velocity, axis_point,
// ramp_time; registered in src/boundary/registry.cpp). Keys are read only where present, so
// the resolved scene of a block without them is unchanged; a scene without a moving block
// builds nothing.
template <int D>
void buildMovingWalls(BoundaryBuild<D>& b) {
  std::vector<ConfigTable> tables = b.root.tableArray("blocks");
  if (tables.size() != b.blocks.size()) throw std::logic_error("moving walls: the blocks' particle spans do not match");
  std::vector<WallMotion<D>> motions;
  const std::size_t n0 = b.particles.n_moving;
  for (std::size_t k = 0; k < tables.size(); ++k) {
    ConfigTable& t = tables[k];
    const BlockParticles& span = b.blocks[k];
    if (!span.wall) {
      for (const char* key : kMotionKeys)
        if (t.has(key))
          t.fail(key, std::string("no ") + key + " on a fluid block (a prescribed rigid motion is for kind = \"wall\"; "
                      "a fluid block's velocity is its initial velocity)");
      continue;
    }
    if (t.has("axis_point") && !t.has("angular_velocity"))
      t.fail("axis_point", "no axis_point without angular_velocity (the point the wall rotates about)");
    if (std::none_of(std::begin(kWallMotionKeys), std::end(kWallMotionKeys), [&](const char* key) { return t.has(key); }))
      continue;
    WallMotion<D> m;
    if (t.has("velocity")) m.velocity = t.vector<D>("velocity", std::nullopt, "m/s");
    if (t.has("angular_velocity")) {
      if constexpr (D == 2) {
        m.angular_velocity[2] = t.number("angular_velocity", std::nullopt, Bound::any,
                                         "rad/s; in 2D one number, the rotation about z, counter-clockwise positive");
      } else {
        const Vec<3> w = t.vector<3>("angular_velocity", std::nullopt, "rad/s; in 3D the vector omega");
        m.angular_velocity = w;
      }
      if (!t.has("axis_point"))
        t.fail("angular_velocity", "an axis_point with angular_velocity (the point, m, the rotation axis passes through)");
      m.axis_point = t.vector<D>("axis_point", std::nullopt, "m");
      if (m.rotates() && span.image)
        t.fail("angular_velocity", "no rotation with treatment = \"image\" (its normals are fixed; use the dummy layers)");
    }
    if (t.has("ramp_time")) m.ramp_time = t.number("ramp_time", std::nullopt, Bound::nonnegative, "s");
    for (int a = 0; a < D; ++a)
      if (!std::isfinite(m.velocity[a])) t.fail("velocity", "a finite velocity, m/s");
    for (int a = 0; a < 3; ++a)
      if (!std::isfinite(m.angular_velocity[a])) t.fail("angular_velocity", "a finite angular velocity, rad/s");
    for (int a = 0; a < D; ++a)
      if (!std::isfinite(m.axis_point[a])) t.fail("axis_point", "a finite point, m");
    if (!m.rotates() && m.velocity.squaredNorm() == 0) {  // at rest: a plain wall
      if (t.has("ramp_time"))
        t.fail("ramp_time", "no ramp_time on a wall at rest (give the wall a velocity or an angular_velocity)");
      continue;
    }
    if (span.first < n0) throw std::logic_error("moving walls: a wall block among the moving particles");
    m.first = span.first - n0;
    m.count = span.count;
    motions.push_back(m);
  }
  if (motions.empty()) return;
  std::vector<double> reference(D * b.particles.nFixed(), 0.0);
  for (std::size_t k = 0; k < b.particles.nFixed(); ++k)
    for (int a = 0; a < D; ++a) reference[D * k + a] = b.particles.position[D * (n0 + k) + a];
  for (const WallMotion<D>& m : motions) {
    // A bound of the wall speed at every time, |U| + max |omega x r| over the block (|omega x r|
    // is kept by the rotation about omega): the velocity scale of a fluid at rest.
    double spin = 0;
    for (std::size_t k = m.first; k < m.first + m.count; ++k) {
      Vec<D> x0, x, u, a;
      for (int c = 0; c < D; ++c) x0[c] = reference[D * k + c];
      WallMotion<D> rotation = m;
      rotation.ramp_time = 0;
      rotation.velocity.setZero();
      MovingWalls<D>::kinematics(rotation, 0.0, x0, x, u, a);
      spin = std::max(spin, u.norm());
    }
    b.facts.prescribed_peak_speed = std::max(b.facts.prescribed_peak_speed, m.velocity.norm() + spin);
  }
  b.boundaries.push_back(std::make_unique<MovingWalls<D>>(std::move(motions), std::move(reference), b.domain));
}

template void buildMovingWalls<2>(BoundaryBuild<2>&);
template void buildMovingWalls<3>(BoundaryBuild<3>&);

}  // namespace vesph
