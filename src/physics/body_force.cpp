// A constant body acceleration g (m/s^2) on every moving particle: the driving force of the
// channel flows (thesis 4.3: F^B models the hydrostatic part of the pressure gradient) and
// gravity. With region_min / region_max, only on the particles inside that box: the die-swell
// feed of the thesis (§4.4: "Body force is applied only to fluid particles within the
// channel"; beyond the die exit the extrudate moves under the push of the fluid behind it).
#include <cmath>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class BodyForce final : public Effect<D> {
 public:
  explicit BodyForce(ConfigTable& cfg) : g_(cfg.vector<D>("acceleration", std::nullopt, "m/s^2")) {
    if (cfg.has("region_min") || cfg.has("region_max")) {
      lo_ = cfg.vector<D>("region_min", std::nullopt, "m");
      hi_ = cfg.vector<D>("region_max", std::nullopt, "m");
      for (int a = 0; a < D; ++a)
        if (!(hi_[a] > lo_[a])) cfg.fail("region_max", "a corner above region_min along every axis");
      region_ = true;
    }
  }
  std::string_view name() const override { return "body_force"; }
  Phase phase() const override { return Phase::external; }
  Vec<D> bodyAcceleration() const override { return g_; }

  void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    if (region_) {
      const double* x = ctx.particles.position.data();
      for (std::size_t i = begin; i < end; ++i) {
        bool inside = true;
        for (int a = 0; a < D; ++a) inside = inside && x[D * i + a] >= lo_[a] && x[D * i + a] <= hi_[a];
        if (inside)
          for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += g_[a];
      }
      return;
    }
    for (std::size_t i = begin; i < end; ++i)
      for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += g_[a];
  }

 private:
  Vec<D> g_;
  bool region_ = false;
  Vec<D> lo_ = Vec<D>::Zero(), hi_ = Vec<D>::Zero();
};

}  // namespace
VESPH_EFFECT_FACTORY(makeBodyForce, BodyForce)
}  // namespace vesph
