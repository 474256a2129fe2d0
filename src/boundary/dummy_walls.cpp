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
  }
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
    // Fang eq. (46): normalised interpolation with the volumes m_f/rho_f.
    for (Field* fp : interpolated_) {
      Field& f = *fp;
      const int nc = f.components;
      double* out = f.data.data() + static_cast<std::size_t>(nc) * w;
      double vol_w = 0;
      for (int c = 0; c < nc; ++c) out[c] = 0.0;
      for (const Neighbour<D>& nb : fluid) {
        const double vw = p.mass[nb.j] / p.density[nb.j] * nb.W;
        vol_w += vw;
        const double* src = f.data.data() + static_cast<std::size_t>(nc) * nb.j;
        for (int c = 0; c < nc; ++c) out[c] += vw * src[c];
      }
      if (vol_w > 0)
        for (int c = 0; c < nc; ++c) out[c] /= vol_w;
    }
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
