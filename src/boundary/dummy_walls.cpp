#include "vesph/boundary/dummy_walls.hpp"

namespace vesph {

template <int D>
void DummyWalls<D>::setup(Setup<D>& s) {
  wall_velocity_ = &s.particles.fields.require("wall_velocity", D, Field::Range::fixed);
  model_ = s.pressure_model;
  if (model_) pressure_ = &s.particles.fields.require("pressure", 1);
  g_ = s.body_acceleration;
  rho0_ = s.rest_density;
}

template <int D>
void DummyWalls<D>::update(const RhsContext<D>& ctx, const NeighbourList<D>& list,
                           PairDriver<D>& driver) {
  ParticleSet<D>& p = ctx.particles;
  const std::size_t n0 = p.n_moving;
  double* wv = wall_velocity_->data.data();
  double* pres = pressure_ ? pressure_->data.data() : nullptr;
  driver.runFixed(ctx, list, [&](Index w, std::span<const Neighbour<D>> fluid) {
    double sumW = 0, sum_p = 0, sum_rho_gr = 0;
    Vec<D> sum_v = Vec<D>::Zero();
    for (const Neighbour<D>& nb : fluid) {
      sumW += nb.W;
      sum_v += nb.W * p.v(nb.j);
      if (pres) sum_p += pres[nb.j] * nb.W;
      sum_rho_gr += p.density[nb.j] * g_.dot(nb.rij) * nb.W;  // rij = r_w - r_f
    }
    double* out_v = wv + D * (w - n0);
    if (sumW > 0) {
      for (int a = 0; a < D; ++a) out_v[a] = 2.0 * p.velocity[D * w + a] - sum_v[a] / sumW;
      if (pres) {
        pres[w] = (sum_p + sum_rho_gr) / sumW;
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
}

template class DummyWalls<2>;
template class DummyWalls<3>;

}  // namespace vesph
