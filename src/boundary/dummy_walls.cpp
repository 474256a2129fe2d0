#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/boundary/registry.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>  // cross products

#include "vesph/core/types.hpp"
#include "vesph/physics/constitutive.hpp"  // packed symmetric tensors

namespace vesph {

template <int D>
void DummyWalls<D>::setup(Setup<D>& s) {
  wall_velocity_ = &s.particles.fields.require("wall_velocity", D, Field::Range::fixed);
  model_ = s.pressure_model;
  if (model_) pressure_ = &s.particles.fields.require("pressure", 1);
  g_ = s.body_acceleration;
  // Moving walls (set up before, vesph/boundary/moving_walls.hpp) give the walls' acceleration.
  acceleration_ = s.particles.fields.find("wall_acceleration");
  spin_ = s.particles.fields.find("wall_spin");
  rho0_ = s.rest_density;
  dx_ = s.spacing;
  const std::size_t n0 = s.particles.n_moving;
  if (!points_.empty() && points_.size() != s.particles.size() - n0)
    throw std::logic_error("wall treatment given for a different number of fixed particles");
  for (const WallPoint<D>& w : points_) {
    any_floor_ = any_floor_ || std::isfinite(w.pressure_floor);
    any_polar_ = any_polar_ || w.polar;
    any_free_slip_ = any_free_slip_ || w.free_slip;
  }
  if (any_floor_ && !model_)
    throw InputError("blocks: pressure_floor bounds the wall pressure extrapolated from the equation of state; "
                     "the scene has none (add [effects.equation_of_state] or remove pressure_floor)");
  for (std::size_t k = 0; k < points_.size(); ++k)
    if (points_[k].image) {
      any_image_ = true;
      if (points_[k].depth > 0) images_.push_back(static_cast<Index>(n0 + k));
    }
  if (!points_.empty() && !any_image_) {
    point_field_ = &s.particles.fields.require("wall_point", kPointComponents, Field::Range::fixed);
    point_field_->refreshed_in_halo = false;  // set once; the ghosts get it with the halo
  }
  // Wetted faces: the pair loop (WettedFaces, vesph/core/pair_loop.hpp) reads the record of
  // each fixed particle from this field, which travels with it in a distributed run.
  if (std::any_of(points_.begin(), points_.end(), [](const WallPoint<D>& w) { return w.wetted_axis >= 0; })) {
    wetted_field_ = &s.particles.fields.require(WettedFaces<D>::kField, WettedFaces<D>::kComponents, Field::Range::fixed);
    wetted_field_->refreshed_in_halo = false;  // set once; the ghosts get it with the halo
  }
}

template <int D>
void DummyWalls<D>::fieldsAllocated(ParticleSet<D>&) {
  if (wetted_field_)
    for (std::size_t k = 0; k < points_.size(); ++k) {
      const WallPoint<D>& w = points_[k];
      double* f = wetted_field_->at(k);
      f[0] = static_cast<double>(w.wetted_axis + 1);
      for (int a = 0; a < D; ++a) {
        f[1 + a] = w.box_lo[a];
        f[1 + D + a] = w.box_hi[a];
      }
    }
  if (!point_field_) return;
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const WallPoint<D>& w = points_[k];
    double* f = point_field_->at(k);
    f[0] = w.polar ? 1.0 : 0.0;
    f[1] = w.linear_stress ? 1.0 : 0.0;
    f[2] = w.centroid ? 1.0 : 0.0;
    f[3] = w.pressure_floor;
    for (int a = 0; a < D; ++a) {
      f[4 + a] = w.axis_point[a];
      f[4 + D + a] = w.axis[a];
    }
    f[4 + 2 * D] = w.free_slip ? 1.0 : 0.0;
  }
}

namespace {
// The index of the diagonal component (a, a) in the packed symmetric storage of
// include/vesph/physics/constitutive.hpp: 2D xx, xy, yy; 3D xx, xy, xz, yy, yz, zz.
template <int D>
int diagonalComponent(int a) {
  if constexpr (D == 2) return a == 0 ? 0 : 2;
  else return a == 0 ? 0 : a == 1 ? 3 : 5;
}

template <int D>
using Rotation = Eigen::Matrix<double, D, D>;

// The rotation about the polar wall's axis that takes the azimuth of x_f to that of x_w
// (dummy_walls.hpp, frame = "polar"): cos and sin of the angle between the two radial
// directions, then R = [[c, -s], [s, c]] (2D, about z) or Rodrigues' c I + s [e]x + (1 - c) e e^T
// (3D, about the unit axis e). The identity when either point lies within `tiny` (m) of the axis.
template <int D>
Rotation<D> azimuthalRotation(const WallPoint<D>& wp, const Vec<D>& xw, const Vec<D>& xf, double tiny) {
  Vec<D> rw = xw - wp.axis_point, rf = xf - wp.axis_point;
  if constexpr (D == 3) {
    rw -= rw.dot(wp.axis) * wp.axis;
    rf -= rf.dot(wp.axis) * wp.axis;
  }
  const double nw = rw.norm(), nf = rf.norm();
  if (!(nw > tiny && nf > tiny)) return Rotation<D>::Identity();
  const double nn = nw * nf;
  const double c = rw.dot(rf) / nn;
  Rotation<D> R;
  if constexpr (D == 2) {
    const double s = (rf[0] * rw[1] - rf[1] * rw[0]) / nn;
    R << c, -s, s, c;
  } else {
    const Vec<3>& e = wp.axis;
    const double s = e.dot(rf.cross(rw)) / nn;
    Rotation<3> K;
    K << 0, -e[2], e[1], e[2], 0, -e[0], -e[1], e[0], 0;
    R = c * Rotation<3>::Identity() + s * K + (1.0 - c) * e * e.transpose();
  }
  return R;
}

// A field's value at one particle turned by R (Field::Transform) into out.
template <int D>
void rotatedValue(const Field& f, const double* src, const Rotation<D>& R, double* out) {
  switch (f.transform) {
    case Field::Transform::vector: {
      const Vec<D> v = R * Eigen::Map<const Vec<D>>(src);
      for (int a = 0; a < D; ++a) out[a] = v[a];
      return;
    }
    case Field::Transform::symmetric_tensor:
      packSymmetric<D>(R * unpackSymmetric<D>(src) * R.transpose(), out);
      return;
    case Field::Transform::tensor: {
      const Rotation<D> T = R * Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(src) * R.transpose();
      Eigen::Map<Eigen::Matrix<double, D, D, Eigen::RowMajor>> target(out);
      target = T;
      return;
    }
    case Field::Transform::invariant:
      for (int c = 0; c < f.components; ++c) out[c] = src[c];
      return;
  }
}
}  // namespace

template <int D>
void DummyWalls<D>::update(const RhsContext<D>& ctx, const NeighbourList<D>& list,
                           PairDriver<D>& driver) {
  ParticleSet<D>& p = ctx.particles;
  const std::size_t n0 = p.n_moving;
  double* wv = wall_velocity_->data.data();
  double* pres = pressure_ ? pressure_->data.data() : nullptr;
  // Fields to interpolate onto the walls, flagged by effects set up after the walls: collected
  // at the first evaluation.
  if (!interpolated_ready_) {
    for (auto& f : p.fields.all())
      if (f->extrapolated_to_walls) {
        if (f->range != Field::Range::all)
          throw std::logic_error("field " + f->name + " is extrapolated to walls but does not cover them");
        interpolated_.push_back(f.get());
      }
    interpolated_ready_ = true;
    if (any_polar_)
      for (const Field* f : interpolated_) {
        const int expected = f->transform == Field::Transform::vector             ? D
                             : f->transform == Field::Transform::symmetric_tensor ? (D == 2 ? 3 : 6)
                             : f->transform == Field::Transform::tensor           ? D * D
                                                                                  : f->components;
        if (f->components != expected || f->components > 9)
          throw std::logic_error("field " + f->name + ": its components do not match its transform");
      }
    for (const Field* f : interpolated_)
      if (any_image_ && (interpolated_.size() > 8 || f->components > 8))
        throw std::logic_error("image walls interpolate at most 8 fields of at most 8 components");
    // The second-order fluid's wall ghost of the lagged acceleration is the no-slip one (-a~,
    // vesph/physics/second_order_fluid.cpp), which a free-slip wall would contradict.
    if (any_free_slip_)
      for (const Field* f : interpolated_)
        if (f->name == "lagged_acceleration")
          throw InputError("blocks: slip = \"free\" is not implemented with the second-order fluid's lagged acceleration "
                           "(its wall ghost is the no-slip one); use slip = \"no\"");
    // Fang: "the normal component of the elastic stress ... is set to zero" on the boundary
    // particles: the stress tensors (D (D + 1) / 2 components).
    for (Field* f : interpolated_)
      is_stress_.push_back((f->name == "elastic_stress" || f->name == "extra_stress") && f->components == (D == 2 ? 3 : 6));
  }
  driver.runFixed(ctx, list, [&](Index w, std::span<const Neighbour<D>> fluid) {
    if (any_image_ && points_[w - n0].image) {
      if (points_[w - n0].depth > 0) return;  // image particles: after the boundary particles
      // Boundary particle on the wall surface: Fang eq. (46) for the pressure and the
      // stresses, n.S.n = 0, the wall's own velocity, rho0.
      const Vec<D>& nrm = points_[w - n0].normal;
      int axis = 0;
      for (int a = 0; a < D; ++a)
        if (nrm[a] != 0.0) axis = a;
      const double vol_w = interpolateFields(p, w, fluid, nullptr);
      for (std::size_t q = 0; q < interpolated_.size(); ++q)
        if (is_stress_[q]) interpolated_[q]->data[static_cast<std::size_t>(interpolated_[q]->components) * w +
                                                  static_cast<std::size_t>(diagonalComponent<D>(axis))] = 0.0;
      double sum_p = 0;
      if (pres)
        for (const Neighbour<D>& nb : fluid) sum_p += p.mass[nb.j] / p.density[nb.j] * nb.W * pres[nb.j];
      double* out_v = wv + D * (w - n0);
      for (int a = 0; a < D; ++a) out_v[a] = p.velocity[D * w + a];
      p.density[w] = rho0_;
      if (pres) pres[w] = vol_w > 0 ? sum_p / vol_w : model_->pressure(rho0_);
      return;
    }
    // An inflow buffer particle is fluid upstream with a prescribed velocity: it carries its
    // own velocity (a Dirichlet value), not the no-slip mirror of a wall, and the fluid's
    // pressure without the hydrostatic term (a zero-gradient inlet: a wall's term would balance
    // the body force at the inlet and hold the fluid back like a wall does).
    const bool inflow = p.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow);
    double* out_v = wv + D * (w - n0);
    const WallPoint<D>* point = points_.empty() ? nullptr : &points_[w - n0];
    const WallPoint<D>* polar = any_polar_ && point->polar ? point : nullptr;
    interpolateFields(p, w, fluid, point);
    if (inflow && ambient_inlet_) {  // a pressure inlet: the ambient pressure, rho0
      for (int a = 0; a < D; ++a) out_v[a] = p.velocity[D * w + a];
      if (pres) {
        p.density[w] = rho0_;
        pres[w] = model_->pressure(rho0_);
      }
      return;
    }
    double sumW = 0, sum_p = 0, sum_rho_gr = 0;
    Vec<D> sum_v = Vec<D>::Zero();
    // g - a_w (Adami eq. 27) for a moving wall; g alone (a_w = 0) otherwise.
    Vec<D> g_rel = g_;
    if (acceleration_)
      for (int a = 0; a < D; ++a) g_rel[a] -= acceleration_->data[D * (w - n0) + a];
    // In a polar frame the fluid's velocities and positions turned to the wall particle's
    // azimuth (dummy_walls.hpp); the pressure's hydrostatic term keeps the true offsets.
    Vec<D> centroid = Vec<D>::Zero();  // x~_f - x_w = -sum_f W rij / sum_f W (turned: polar)
    const Vec<D> xw = p.x(w);
    for (const Neighbour<D>& nb : fluid) {
      sumW += nb.W;
      if (polar) {
        const Rotation<D> R = azimuthalRotation(*polar, xw, Vec<D>(xw - nb.rij), 1e-6 * dx_);
        sum_v += nb.W * (R * p.v(nb.j));
        centroid += nb.W * (R * (xw - nb.rij - polar->axis_point) + polar->axis_point - xw);
      } else {
        sum_v += nb.W * p.v(nb.j);
        centroid -= nb.W * nb.rij;
      }
      if (pres) sum_p += pres[nb.j] * nb.W;
      if (!inflow) sum_rho_gr += p.density[nb.j] * g_rel.dot(nb.rij) * nb.W;  // rij = r_w - r_f
    }
    if (sumW > 0) {
      if (any_free_slip_ && point->free_slip && !inflow) {
        // Free slip (a wall at rest): v~ reflected in the plane normal to the direction of the
        // fluid's centroid (dummy_walls.hpp); without a direction (the centroid on the wall
        // particle) v~ itself.
        const Vec<D> v_mean = sum_v / sumW;
        const double reach = centroid.norm();
        const Vec<D> n = reach > 1e-9 * sumW * dx_ ? Vec<D>(centroid / reach) : Vec<D>::Zero();
        const Vec<D> ghost = v_mean - 2.0 * v_mean.dot(n) * n;
        for (int a = 0; a < D; ++a) out_v[a] = ghost[a];
      } else {
        for (int a = 0; a < D; ++a) out_v[a] = inflow ? p.velocity[D * w + a] : 2.0 * p.velocity[D * w + a] - sum_v[a] / sumW;
      }
      // A rotating wall: the mirror of the fluid's velocity relative to the rigid motion, whose
      // Shepard average over the fluid is u_w + Omega x (x~_f - x_w) (theory.md §6.2).
      if (spin_ && !inflow) {
        centroid /= sumW;
        const double* om = spin_->data.data() + static_cast<std::size_t>(spin_->components) * (w - n0);
        if constexpr (D == 2) {
          out_v[0] += -om[0] * centroid[1];
          out_v[1] += om[0] * centroid[0];
        } else {
          out_v[0] += om[1] * centroid[2] - om[2] * centroid[1];
          out_v[1] += om[2] * centroid[0] - om[0] * centroid[2];
          out_v[2] += om[0] * centroid[1] - om[1] * centroid[0];
        }
      }
      if (pres) {
        pres[w] = (sum_p + sum_rho_gr) / sumW;
        // A non-adhesive wall: a fluid in tension near it (a die's lip, where the extrudate's
        // surface rows are stretched) would give it a negative pressure, and the symmetric
        // pressure force would pull the fluid onto the wall.
        if (any_floor_ && !inflow) pres[w] = std::max(pres[w], points_[w - n0].pressure_floor);
        p.density[w] = model_->densityFor(pres[w]);
      }
    } else {
      for (int a = 0; a < D; ++a) out_v[a] = p.velocity[D * w + a];
      if (pres) {
        p.density[w] = rho0_;
        pres[w] = model_->pressure(rho0_);
      }
    }
  });
  if (images_.empty()) return;
#pragma omp parallel for schedule(static) if (images_.size() >= kParallelMinimum)
  for (std::size_t k = 0; k < images_.size(); ++k) imageParticle(ctx, list, images_[k]);
}

template <int D>
void DummyWalls<D>::velocityDependence(const ParticleSet<D>& p, std::vector<double>& dependence) const {
  const std::size_t n0 = p.n_moving;
  for (std::size_t w = n0; w < p.size(); ++w) {
    if (any_image_ && points_[w - n0].image) continue;
    if (p.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow)) continue;
    dependence[w - n0] = !points_.empty() && points_[w - n0].free_slip ? 1.0 : -1.0;
  }
}

template <int D>
double DummyWalls<D>::interpolateFields(ParticleSet<D>& p, Index w, std::span<const Neighbour<D>> fluid,
                                        const WallPoint<D>* point) const {
  // Fang eq. (46): the normalised interpolation with the volumes m_f/rho_f, for every flagged
  // field (0 without fluid neighbours). Returns the weight sum sum_f (m_f/rho_f) W_wf. In a
  // polar frame each fluid value is first turned to the wall particle's azimuth.
  const WallPoint<D>* polar = point && point->polar ? point : nullptr;
  double vol_w = 0;
  Vec<D> mean_offset = Vec<D>::Zero();  // d~ = sum_f V_f W_wf (x_f - x_w) / vol_w
  for (const Neighbour<D>& nb : fluid) {
    const double vw = p.mass[nb.j] / p.density[nb.j] * nb.W;
    vol_w += vw;
    mean_offset -= vw * nb.rij;
  }
  // stress_extrapolation = "linear": the weights c_f = V_f W_wf (1/vol_w - (d_f - d~) . a),
  // a = M^-1 d~, M = sum_f V_f W_wf (d_f - d~)(d_f - d~)^T, give f_w = f~ - d~ . G with G the
  // weighted least-squares gradient of the fluid's values: the linear continuation of the field
  // to the wall particle (exact for a linear field; sum_f c_f = 1, sum_f c_f d_f = 0). Where the
  // fluid neighbours do not spread along every direction (the smallest eigenvalue of M/vol_w
  // below (dx/5)^2: a deep dummy particle that reaches one fluid row) the Shepard average stays.
  Vec<D> a = Vec<D>::Zero();
  bool continued = false;  // the linear weights apply (else the plain average, as eq. 46 sums it)
  if (vol_w > 0) {
    mean_offset /= vol_w;
    if (point && point->linear_stress) {
      Rotation<D> M = Rotation<D>::Zero();
      for (const Neighbour<D>& nb : fluid) {
        const Vec<D> d = -nb.rij - mean_offset;
        M += (p.mass[nb.j] / p.density[nb.j] * nb.W) * d * d.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Rotation<D>> eig(M / vol_w, Eigen::EigenvaluesOnly);
      if (eig.eigenvalues().minCoeff() > 0.04 * dx_ * dx_) {
        a = M.ldlt().solve(mean_offset);
        continued = true;
      }
    }
  }
  for (Field* f : interpolated_)
    for (int c = 0; c < f->components; ++c) f->data[static_cast<std::size_t>(f->components) * w + c] = 0.0;
  if (!(vol_w > 0)) return vol_w;
  // Neighbours outer, fields inner: one weight and one rotation per neighbour (each field's sum
  // runs over the neighbours in the same order as eq. 46 alone).
  const Vec<D> xw = p.x(w);
  for (const Neighbour<D>& nb : fluid) {
    const double vw = p.mass[nb.j] / p.density[nb.j] * nb.W;
    const double weight = continued ? vw * (1.0 / vol_w - (-nb.rij - mean_offset).dot(a)) : vw;
    const Rotation<D> R = polar ? azimuthalRotation(*polar, xw, Vec<D>(xw - nb.rij), 1e-6 * dx_)
                                : Rotation<D>::Identity();
    for (Field* fp : interpolated_) {
      Field& f = *fp;
      const int nc = f.components;
      double* out = f.data.data() + static_cast<std::size_t>(nc) * w;
      const double* src = f.data.data() + static_cast<std::size_t>(nc) * nb.j;
      if (polar && f.transform != Field::Transform::invariant) {
        double turned[9];  // at most D x D components (checked at the first update)
        rotatedValue<D>(f, src, R, turned);
        for (int c = 0; c < nc; ++c) out[c] += weight * turned[c];
        continue;
      }
      for (int c = 0; c < nc; ++c) out[c] += weight * src[c];
    }
  }
  if (!continued)
    for (Field* f : interpolated_)
      for (int c = 0; c < f->components; ++c) f->data[static_cast<std::size_t>(f->components) * w + c] /= vol_w;
  return vol_w;
}

template <int D>
void DummyWalls<D>::imageParticle(const RhsContext<D>& ctx, const NeighbourList<D>& list, Index w) {
  // Fang eqs. (46)-(48): values at P = r_B + d_P n by (46), extrapolated through the wall
  // value (boundary particle B) to the image particle's depth d_I.
  ParticleSet<D>& p = ctx.particles;
  const std::size_t n0 = p.n_moving;
  const WallPoint<D>& wp = points_[w - n0];
  const Index b = wp.boundary;
  const double d_p = dx_;
  Vec<D> xp;
  for (int a = 0; a < D; ++a) xp[a] = p.position[D * b + a] + d_p * wp.normal[a];
  double vol_w = 0, sum_p = 0;
  Vec<D> sum_v = Vec<D>::Zero(), sum_r = Vec<D>::Zero();
  constexpr int kMaxComponents = 8;
  double sum_f[8][kMaxComponents] = {};
  const double* pres = pressure_ ? pressure_->data.data() : nullptr;
  const std::size_t nf = interpolated_.size();  // <= 8, checked at the first update
  list.forMovingNear(p, xp, [&](Index j, const Vec<D>& r) {
    const double vw = p.mass[j] / p.density[j] * ctx.kernel.W(r.norm());
    vol_w += vw;
    sum_v += vw * p.v(j);
    sum_r -= vw * r;  // r = x_P - x_j
    if (pres) sum_p += vw * pres[j];
    for (std::size_t q = 0; q < nf; ++q) {
      const Field& f = *interpolated_[q];
      const double* src = f.data.data() + static_cast<std::size_t>(f.components) * j;
      for (int c = 0; c < f.components && c < kMaxComponents; ++c) sum_f[q][c] += vw * src[c];
    }
  });
  double* out_v = wall_velocity_->data.data() + D * (w - n0);
  p.density[w] = rho0_;
  if (vol_w <= 0) {  // no fluid near P: the wall values
    for (int a = 0; a < D; ++a) out_v[a] = p.velocity[D * b + a];
    if (pres) pressure_->data[w] = pres[b];
    for (std::size_t q = 0; q < interpolated_.size(); ++q) {
      Field& f = *interpolated_[q];
      for (int c = 0; c < f.components; ++c) f.data[f.components * w + c] = f.data[f.components * b + c];
    }
    return;
  }
  const double inv = 1.0 / vol_w;
  // The interpolation (46) at P over a support cut by the wall is the value at the centroid
  // of its weights, not at P: the extrapolation uses that centroid's distance from the wall
  // (first-order consistent; with d_P itself a linear profile's wall slope is off by the bias).
  const double d_c = wp.centroid ? d_p + (sum_r * inv).dot(wp.normal) : d_p;
  const double factor = 1.0 + wp.depth / std::max(d_c, 0.25 * d_p);
  for (int a = 0; a < D; ++a) {
    const double vp = sum_v[a] * inv;
    out_v[a] = vp + factor * (p.velocity[D * b + a] - vp);  // eq. (47), u_w the wall's velocity
  }
  if (pres) pressure_->data[w] = sum_p * inv + factor * (pres[b] - sum_p * inv);
  for (std::size_t q = 0; q < nf; ++q) {  // eq. (48)
    Field& f = *interpolated_[q];
    const int nc = f.components;
    for (int c = 0; c < nc && c < kMaxComponents; ++c) {
      const double fp = sum_f[q][c] * inv;
      f.data[static_cast<std::size_t>(nc) * w + c] = fp + factor * (f.data[static_cast<std::size_t>(nc) * b + c] - fp);
    }
  }
}

template <int D>
void DummyWalls<D>::resized(const ParticleRemap& remap) {
  if (point_field_) {  // the set's fixed particles as they are now (a redistribution moves them)
    points_.assign(point_field_->data.size() / kPointComponents, WallPoint<D>{});
    for (std::size_t k = 0; k < points_.size(); ++k) {
      const double* f = point_field_->at(k);
      WallPoint<D>& w = points_[k];
      w.polar = f[0] > 0.5;
      w.linear_stress = f[1] > 0.5;
      w.centroid = f[2] > 0.5;
      w.pressure_floor = f[3];
      for (int a = 0; a < D; ++a) {
        w.axis_point[a] = f[4 + a];
        w.axis[a] = f[4 + D + a];
      }
      w.free_slip = f[4 + 2 * D] > 0.5;
      any_free_slip_ = any_free_slip_ || w.free_slip;
    }
    return;
  }
  // Fixed particles keep their order; their indices move with the count of moving ones.
  for (Index& w : images_) w = remap.fixedIndex(w);
  for (WallPoint<D>& wp : points_)
    if (wp.image) wp.boundary = remap.fixedIndex(wp.boundary);
}

template class DummyWalls<2>;
template class DummyWalls<3>;

}  // namespace vesph

namespace vesph {

// The walls of the scene's blocks (src/boundary/registry.cpp): every fixed particle is a wall
// particle, the inflow buffer's too (it is built before: no image treatment for it).
template <int D>
void buildDummyWalls(BoundaryBuild<D>& b) {
  if (!b.wall_points.empty()) b.wall_points.resize(b.particles.nFixed());
  if (b.particles.nFixed() > 0)
    b.boundaries.push_back(std::make_unique<DummyWalls<D>>(b.wall_points, b.facts.extrapolated_inflow));
}

template void buildDummyWalls<2>(BoundaryBuild<2>&);
template void buildDummyWalls<3>(BoundaryBuild<3>&);

}  // namespace vesph
