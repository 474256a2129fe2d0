#pragma once
// Structure-of-arrays particle storage (DESIGN.md "ParticleSet").
// Particles [0, n_moving) move and form the ODE state; [n_moving, size()) are fixed
// (walls, dummy layers). Always present: position, velocity, density, mass, kind, id.
// Every other field (pressure, extra stress, free-surface flag, ...) exists only when an
// active effect requests it through fields.require().
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

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

template <int D>
struct ParticleSet {
  std::size_t n_moving = 0;
  std::vector<double> position;  // [N*D]
  std::vector<double> velocity;  // [N*D]
  std::vector<double> density;   // [N]
  std::vector<double> mass;      // [N]
  std::vector<std::uint8_t> kind;
  std::vector<std::uint64_t> id;
  FieldStore fields;

  std::size_t size() const { return mass.size(); }
  std::size_t nFixed() const { return size() - n_moving; }

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
};

}  // namespace vesph
