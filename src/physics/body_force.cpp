// A constant body acceleration g (m/s^2) on every moving particle: the driving force of the
// channel flows (thesis 4.3: F^B models the hydrostatic part of the pressure gradient) and
// gravity.
#include <cmath>

#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
class BodyForce final : public Effect<D> {
 public:
  explicit BodyForce(ConfigTable& cfg) : g_(cfg.vector<D>("acceleration", std::nullopt, "m/s^2")) {}
  std::string_view name() const override { return "body_force"; }
  Phase phase() const override { return Phase::external; }
  Vec<D> bodyAcceleration() const override { return g_; }

  void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    for (std::size_t i = begin; i < end; ++i)
      for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += g_[a];
  }

 private:
  Vec<D> g_;
};

}  // namespace
VESPH_EFFECT_FACTORY(makeBodyForce, BodyForce)
}  // namespace vesph
