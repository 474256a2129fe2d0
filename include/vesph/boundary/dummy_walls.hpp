#pragma once
// Fixed no-slip walls made of particle layers (thesis 4.2: wall particles plus dummy layers
// at least one kernel radius thick). Wall particles do not evolve; before each force pass
// they are given values extrapolated from the fluid around them, following Adami, Hu &
// Adams (2012, J. Comput. Phys. 231:7057), eqs. (22)-(27):
//   wall_velocity_w = 2 u_w - sum_f v_f W_wf / sum_f W_wf        (no slip on the surface)
//   p_w = [ sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf ] / sum_f W_wf
//   rho_w from the inverse equation of state at p_w
// u_w = 0 (walls at rest), a_w = 0, g the scene's body acceleration. A wall particle with no
// fluid neighbour keeps p0, rho0 and zero velocity. The wall's own velocity (zero) enters the
// continuity equation; the extrapolated velocity enters the viscous term only.
// Fields flagged Field::extrapolated_to_walls (elastic and extra stresses) get the normalised
// SPH interpolation of Fang et al. (2006) eq. (46) from the fluid neighbours:
//   f_w = sum_f (m_f/rho_f) f_f W_wf / sum_f (m_f/rho_f) W_wf
// (zero for a wall particle without fluid neighbours).
#include "vesph/boundary/boundary.hpp"

namespace vesph {

template <int D>
class DummyWalls final : public Boundary<D> {
 public:
  std::string_view name() const override { return "dummy_walls"; }
  void setup(Setup<D>& s) override;
  void update(const RhsContext<D>& ctx, const NeighbourList<D>& list, PairDriver<D>& driver) override;

 private:
  Field* wall_velocity_ = nullptr;
  std::vector<Field*> interpolated_;
  bool interpolated_ready_ = false;
  Field* pressure_ = nullptr;
  const PressureModel* model_ = nullptr;
  Vec<D> g_ = Vec<D>::Zero();
  double rho0_ = 1;
};

}  // namespace vesph
