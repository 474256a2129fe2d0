#pragma once
// Names map to factories (docs/architecture.md "Effects"): a scene switches an effect on by giving its
// table, [effects.<name>]. The registry lists every effect; src/physics/registry.cpp holds
// one registration line per effect.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vesph/io/config.hpp"
#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
using EffectFactory = std::unique_ptr<Effect<D>> (*)(ConfigTable&);

template <int D>
struct EffectEntry {
  std::string name;
  std::string summary;
  EffectFactory<D> make;
};

template <int D>
const std::vector<EffectEntry<D>>& effectRegistry();

// Builds the effects named in the scene's [effects] table (in the alphabetical order of their
// names, as the TOML table keeps them; within a phase contributions are summed, so order does
// not matter).
template <int D>
std::vector<std::unique_ptr<Effect<D>>> makeEffects(ConfigTable& effects_table);

}  // namespace vesph

// In an effect's source file: defines the factory for both dimensions.
#define VESPH_EFFECT_FACTORY(FN, TYPE)                                          \
  template <int D>                                                              \
  std::unique_ptr<::vesph::Effect<D>> FN(::vesph::ConfigTable& cfg) {          \
    return std::make_unique<TYPE<D>>(cfg);                                      \
  }                                                                             \
  template std::unique_ptr<::vesph::Effect<2>> FN<2>(::vesph::ConfigTable&);    \
  template std::unique_ptr<::vesph::Effect<3>> FN<3>(::vesph::ConfigTable&);
