#pragma once
// Structure-of-arrays particle storage (docs/architecture.md "The shape").
// Particles [0, n_moving) move and form the ODE state; [n_moving, size()) are fixed
// (walls, dummy layers). Always present: position, velocity, density, mass, kind, id.
// Every other field (pressure, extra stress, free-surface flag, ...) exists only when an
// active effect requests it through fields.require().
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <stdexcept>

#include "vesph/core/types.hpp"

namespace vesph {

// A named per-particle field with `components` doubles per particle, stored contiguously
// (particle-major). `range` says which particles it covers.
struct Field {
  enum class Range { all, moving, fixed };
  std::string name;
  int components = 1;
  Range range = Range::all;
  // Wall particles get this field by the normalised SPH interpolation of Fang et al. eq. (46)
  // from their fluid neighbours (vesph/boundary/dummy_walls.hpp); needs Range::all.
  bool extrapolated_to_walls = false;
  // How the components turn with the frame: walls averaged in a polar frame ([[blocks]]
  // frame = "polar", vesph/boundary/dummy_walls.hpp) rotate each fluid value R f (vector),
  // R S R^T (tensor: packed symmetric D (D + 1) / 2 components, or full D x D row-major) before
  // the average. Scalars (and any field left `invariant`) are averaged as they are.
  enum class Transform { invariant, vector, symmetric_tensor, tensor };
  Transform transform = Transform::invariant;
  // Whether a distributed run's halo refresh copies it to the ghosts (core/distribution.hpp):
  // false for values only the owner reads (the integrator's rates carried through a migration).
  bool refreshed_in_halo = true;
  std::vector<double> data;

  double* at(std::size_t k) { return data.data() + k * components; }
  const double* at(std::size_t k) const { return data.data() + k * components; }
};

class FieldStore {
 public:
  // Returns the field, creating it on first request. A second request must agree on the
  // shape; the pointer stays valid for the life of the store.
  Field& require(const std::string& name, int components, Field::Range range = Field::Range::all);
  Field* find(const std::string& name);
  const Field* find(const std::string& name) const;
  const std::vector<std::unique_ptr<Field>>& all() const { return fields_; }

 private:
  std::vector<std::unique_ptr<Field>> fields_;
};

// A change of the moving set between two steps (an inflow releases particles, an outflow
// removes them; docs/architecture.md "The life of one step"). The fixed particles keep
// their order; fixed particle k (old index old_moving + k) becomes new index newMoving() + k.
struct ParticleRemap {
  std::size_t old_size = 0, old_moving = 0;
  // For each moving particle after the change, in order, the particle (old numbering) whose
  // values it takes: itself for a kept particle, a fixed particle (>= old_moving) for one that
  // an inflow buffer releases into the fluid (it starts with the buffer particle's values).
  std::vector<Index> source;
  std::vector<std::uint64_t> released_ids;  // the ids of the released particles, in order

  std::size_t newMoving() const { return source.size(); }
  std::size_t nFixed() const { return old_size - old_moving; }
  std::size_t newSize() const { return newMoving() + nFixed(); }
  // The new index of an old fixed particle.
  Index fixedIndex(Index old) const { return static_cast<Index>(old - old_moving + newMoving()); }
  // Rewrites per-particle values (comps per particle) laid out over the given range: moving
  // values follow source (a released particle's moving-only value, which its buffer particle
  // does not have, is `fill`); fixed values keep their order.
  template <class T>
  void apply(std::vector<T>& v, int comps, Field::Range range, T fill = T{}) const;
};

template <int D>
struct ParticleSet {
  std::size_t n_moving = 0;
  // A distributed run's ghosts (copies of particles other ranks own, core/distribution.hpp):
  // the last n_ghost_moving of the moving particles and the last n_ghost_fixed of the fixed
  // ones. Neighbour loops visit the owned particles only; the ODE state holds the owned moving
  // ones. Zero in a serial run.
  std::size_t n_ghost_moving = 0, n_ghost_fixed = 0;
  std::vector<double> position;  // [N*D]
  std::vector<double> velocity;  // [N*D]
  std::vector<double> density;   // [N]
  std::vector<double> mass;      // [N]
  std::vector<std::uint8_t> kind;
  std::vector<std::uint64_t> id;
  FieldStore fields;

  std::size_t size() const { return mass.size(); }
  std::size_t nFixed() const { return size() - n_moving; }
  // The moving particles this process owns, [0, ownedMoving()), and the end of the owned fixed
  // ones, [n_moving, ownedEnd()): n_moving and size() in a serial run.
  std::size_t ownedMoving() const { return n_moving - n_ghost_moving; }
  std::size_t ownedEnd() const { return size() - n_ghost_fixed; }

  Eigen::Map<Vec<D>> x(std::size_t i) { return Eigen::Map<Vec<D>>(position.data() + D * i); }
  Eigen::Map<const Vec<D>> x(std::size_t i) const {
    return Eigen::Map<const Vec<D>>(position.data() + D * i);
  }
  Eigen::Map<Vec<D>> v(std::size_t i) { return Eigen::Map<Vec<D>>(velocity.data() + D * i); }
  Eigen::Map<const Vec<D>> v(std::size_t i) const {
    return Eigen::Map<const Vec<D>>(velocity.data() + D * i);
  }

  // Appends one particle; moving particles must all be added before fixed ones.
  void add(const Vec<D>& pos, const Vec<D>& vel, double rho, double m, ParticleKind k,
           std::uint64_t ident);
  // Resizes every registered field to the current particle count.
  void resizeFields();
  // Applies a change of the moving set to every array and field (ParticleRemap). Released
  // particles become kind fluid with the remap's new ids.
  void remapMoving(const ParticleRemap& remap);
};

template <class T>
void ParticleRemap::apply(std::vector<T>& v, int comps, Field::Range range, T fill) const {
  if (range == Field::Range::fixed) return;
  const bool all = range == Field::Range::all;
  const std::size_t c = static_cast<std::size_t>(comps), nm = newMoving();
  const std::size_t old_count = all ? old_size : old_moving;
  if (v.size() != old_count * c) throw std::logic_error("ParticleRemap: values of the wrong length");
  std::vector<T> out((all ? newSize() : nm) * c);
  for (std::size_t i = 0; i < nm; ++i) {
    const std::size_t s = source[i];
    for (std::size_t k = 0; k < c; ++k) out[c * i + k] = (all || s < old_moving) ? v[c * s + k] : fill;
  }
  if (all)
    for (std::size_t f = 0; f < nFixed(); ++f)
      for (std::size_t k = 0; k < c; ++k) out[c * (nm + f) + k] = v[c * (old_moving + f) + k];
  v.swap(out);
}

}  // namespace vesph
