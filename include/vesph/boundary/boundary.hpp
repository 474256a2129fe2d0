#pragma once
// Boundaries act on fixed particles during the right-hand side, after the state phase
// (fluid pressures known) and before the pair passes that read the boundary values.
#include <string_view>

#include "vesph/physics/effect.hpp"
#include "vesph/physics/pair_driver.hpp"

namespace vesph {

template <int D>
class Boundary {
 public:
  virtual ~Boundary() = default;
  virtual std::string_view name() const = 0;
  virtual void setup(Setup<D>& s) = 0;
  virtual void update(const RhsContext<D>& ctx, const NeighbourList<D>& list, PairDriver<D>& driver) = 0;
  // The moving set changed between steps: fixed particles moved to new indices (ParticleRemap).
  virtual void resized(const ParticleRemap& remap) {}
};

}  // namespace vesph
