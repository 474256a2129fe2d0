#pragma once
// Fixed no-slip walls made of particle layers (thesis 4.2: wall particles plus dummy layers
// at least one kernel radius thick). Wall particles do not evolve; before each force pass
// they are given values extrapolated from the fluid around them, following Adami, Hu &
// Adams (2012, J. Comput. Phys. 231:7057), eqs. (22)-(27):
//   wall_velocity_w = 2 u_w - sum_f v_f W_wf / sum_f W_wf        (no slip on the surface)
//   p_w = [ sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf ] / sum_f W_wf
//   rho_w from the inverse equation of state at p_w
// u_w the wall particle's own velocity (0 for walls at rest; a moving wall's prescribed velocity,
// vesph/boundary/moving_walls.hpp), a_w its acceleration (field wall_acceleration of the moving
// walls; 0 without), g the scene's body acceleration. A wall particle with no
// fluid neighbour keeps p0, rho0 and zero velocity. The wall's own velocity (zero) enters the
// continuity equation; the extrapolated velocity enters the viscous term only.
// Fields flagged Field::extrapolated_to_walls (elastic and extra stresses) get the normalised
// SPH interpolation of Fang et al. (2006) eq. (46) from the fluid neighbours:
//   f_w = sum_f (m_f/rho_f) f_f W_wf / sum_f (m_f/rho_f) W_wf
// (zero for a wall particle without fluid neighbours).
//
// Per wall block ([[blocks]] treatment = "image", with its normal), Fang et al. (2006) §3.3
// instead: a row of boundary particles on the wall surface and rows of image particles behind
// it (Fig. 1), all with fixed positions and densities (rho0).
//   boundary particle B (on the surface): velocity u_w (no slip on the wall itself); pressure
//     and stresses by the normalised interpolation (46) from the fluid around it, the normal
//     component n.S.n of the stresses set to zero;
//   image particle I at depth d_I behind the surface: from the point P = r_B + d_P n inside the
//     fluid (d_P = dx, "comparable to the initial smallest separation"), values f_P by (46)
//     from the fluid around P, and the linear extrapolations through the wall value f_W (the
//     boundary particle B of I's column)
//         v_I = v_P + (1 + d_I/d_P) (u_w - v_P)                            (eq. 47)
//         S_I = S_P + (1 + d_I/d_P) (S_W - S_P)                            (eq. 48)
//     and the same for the pressure ("an identical procedure", §3.3).
//     With extrapolation = "centroid" the distance d_P in (47)-(48) is that of the centroid of
//     the interpolation weights at P: over a support cut by the wall, (46) gives the value at
//     that centroid (about 0.2 dx further from the wall), not at P, so the literal d_P
//     ("fang") extrapolates a linear profile with the wrong slope. Measured in the Poiseuille
//     channel: 0.72 % ("fang") against 0.18 % ("centroid") at t = 0.1125 s (validation §1).
//
// Per dummy-layer wall block of a round shape (cylinder, tube, 2D disk) with frame = "polar":
// the fluid's velocities and the fields above are averaged in the block's polar frame. Each
// fluid neighbour's vector f is turned to R f, its tensor S to R S R^T, R the rotation about
// the block's axis that takes the fluid particle's azimuth to the wall particle's (and its
// position to R (x_f - c) + c for the rigid-motion term), so that the averages mean the same
// components (radial, azimuthal, axial) for every neighbour. Near a wall whose radius is a few
// spacings the Cartesian average runs over up to +-90 degrees of azimuth and cancels most of
// an azimuthal velocity or a shear stress (docs/theory.md §6.3: the rod of radius 2 dx passed
// 0.21 of the Couette shear stress to its first fluid ring); for an axisymmetric flow the
// polar average is exact for a uniform field in polar components. A wall particle on the axis
// keeps the Cartesian average (its azimuth is undefined).
// Per dummy-layer wall block with stress_extrapolation = "linear": the flagged fields are not
// the Shepard average of eq. (46), which is the value at the centroid of the fluid neighbours
// (about a support's half-width inside the fluid), but its weighted least-squares linear
// continuation to the wall particle, f_w = f~ + (x_w - x~) . G (docs/theory.md §6.3): the
// stress divergence on the first fluid rows then sees the stress gradient continue into the
// wall, as the viscous term sees the mirrored velocity. Opt-in: a gradient of noisy stresses
// near a free surface is amplified by the extrapolation distance.
// The fluid must start one spacing from the wall surface (Fang's Fig. 1: the fluid lattice
// continues the wall's), i.e. a fluid block's edge half a spacing off the surface.
// The extrapolated velocity is the wall particle's ghost velocity (field wall_velocity, used by
// the viscous and velocity-gradient terms); the continuity equation sees the wall's own
// velocity, as for the dummy layers.
//
// Per dummy-layer wall block at rest with slip = "free": a wall without shear stress. The ghost
// velocity is the reflection of the fluid's Shepard average v~ in the wall's plane,
//   wall_velocity_w = v~ - 2 (v~ . n) n,   n = (x~_f - x_w)/|x~_f - x_w|,
// x~_f the Shepard centroid of the fluid neighbours (the direction into the fluid, in the
// polar frame where the block has one): the tangential velocity continues into the wall (no
// velocity difference across it: no tangential viscous force), the normal one is mirrored (as
// at a no-slip wall, holding the fluid off it with the pressure). It stands for a symmetry plane
// (docs/theory.md §6.4): the floor of the rod-climbing container, under which the theory's fluid
// is infinitely deep (docs/validation.md §20).
#include <limits>
#include <vector>

#include "vesph/boundary/boundary.hpp"

namespace vesph {

// How one fixed particle is treated (in fixed-particle order; DummyWalls takes an empty list
// for a scene of dummy layers only).
template <int D>
struct WallPoint {
  bool image = false;           // Fang's treatment (boundary particle when depth == 0)
  Vec<D> normal = Vec<D>::Zero();  // into the fluid
  double depth = 0;             // behind the wall surface, m
  Index boundary = 0;           // the boundary particle of the column (particle index)
  bool centroid = false;        // extrapolate from the centroid of P's weights (below)
  // Dummy layers: the extrapolated pressure is not allowed below this value (Pa; -inf: no
  // floor). At 0 the wall pushes the fluid but never pulls it (docs/theory.md §6).
  double pressure_floor = -std::numeric_limits<double>::infinity();
  // Dummy layers of a round block averaged in its polar frame (above): the axis through
  // axis_point along axis (3D; in 2D the axis is z and `axis` is unused).
  bool polar = false;
  // Dummy layers, stress_extrapolation = "linear": the flagged fields (stresses) continued
  // linearly from the fluid to the particle instead of Fang eq. (46)'s average (below).
  bool linear_stress = false;
  Vec<D> axis_point = Vec<D>::Zero();
  Vec<D> axis = Vec<D>::Zero();
  // Dummy layers at rest, slip = "free": the ghost velocity is the fluid's reflected in the
  // wall's plane (above) instead of its no-slip mirror.
  bool free_slip = false;
  // Dummy-layer box with wetted_face: the axis of the wetted face's normal (-1: none) and the
  // block's box. A moving particle outside the box along another axis - beyond one of the
  // block's end faces, which are dry, on either side of the wetted plane - does not interact
  // with the block's particles (field wetted_face, read by the pair loop: vesph/core/pair_loop.hpp).
  int wetted_axis = -1;
  Vec<D> box_lo = Vec<D>::Zero(), box_hi = Vec<D>::Zero();
};

template <int D>
class DummyWalls final : public Boundary<D> {
 public:
  // ambient_inlet: inflow buffer particles (kind inflow) take the ambient pressure (that of
  // rho0) instead of the fluid's extrapolated pressure: the pressure inlet that goes with an
  // extrapolated inflow velocity (vesph/boundary/inflow_outflow.hpp).
  explicit DummyWalls(std::vector<WallPoint<D>> points = {}, bool ambient_inlet = false)
      : points_(std::move(points)), ambient_inlet_(ambient_inlet) {}
  std::string_view name() const override { return "dummy_walls"; }
  void setup(Setup<D>& s) override;
  void fieldsAllocated(ParticleSet<D>& particles) override;
  void update(const RhsContext<D>& ctx, const NeighbourList<D>& list, PairDriver<D>& driver) override;
  void resized(const ParticleRemap& remap) override;
  // The no-slip mirror 2 u_w - (the fluid's Shepard average): -1; the boundary particles of
  // image walls and inflow buffers carry prescribed velocities: 0; a free-slip wall: +1 (its
  // tangential components, which carry the shear, follow the fluid's; the mirrored normal one
  // is left to the Krylov iterations).
  void velocityDependence(const ParticleSet<D>& particles, std::vector<double>& dependence) const override;

 private:
  Field* wall_velocity_ = nullptr;
  const Field* acceleration_ = nullptr;  // wall_acceleration (moving walls), or none
  const Field* spin_ = nullptr;          // wall_spin (rotating walls), or none
  std::vector<Field*> interpolated_;
  bool interpolated_ready_ = false;
  Field* pressure_ = nullptr;
  const PressureModel* model_ = nullptr;
  Vec<D> g_ = Vec<D>::Zero();
  double rho0_ = 1, dx_ = 1;
  std::vector<WallPoint<D>> points_;
  // Without image walls, each fixed particle's treatment (polar frame, linear stress, pressure
  // floor, free slip: kPointComponents values) is also a field, so that it travels with the
  // particle in a run across processes: points_ is made again from it after the set changes
  // (resized).
  static constexpr int kPointComponents = 5 + 2 * D;
  Field* point_field_ = nullptr;  // wall_point
  Field* wetted_field_ = nullptr;  // wetted_face (WettedFaces<D>::kComponents per fixed particle), or none
  std::vector<Index> images_;     // the image particles (depth > 0), particle indices
  std::vector<char> is_stress_;   // per interpolated field: a stress tensor (n.S.n = 0 on the wall)
  bool any_image_ = false;
  bool any_floor_ = false;        // some wall particle has a finite pressure_floor
  bool any_polar_ = false;        // some wall particle averages in a polar frame
  bool any_free_slip_ = false;    // some wall particle is free-slip
  bool ambient_inlet_ = false;

  // Fang eq. (46) for the flagged fields, in the wall point's polar frame and/or continued
  // linearly where it says so (point null: neither).
  double interpolateFields(ParticleSet<D>& p, Index w, std::span<const Neighbour<D>> fluid,
                           const WallPoint<D>* point) const;
  void imageParticle(const RhsContext<D>& ctx, const NeighbourList<D>& list, Index w);
};

}  // namespace vesph
