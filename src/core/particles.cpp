#include "vesph/core/particles.hpp"

namespace vesph {

Field& FieldStore::require(const std::string& name, int components, Field::Range range) {
  if (Field* f = find(name)) {
    if (f->components != components || f->range != range)
      throw std::logic_error("field '" + name + "' requested twice with different shapes");
    return *f;
  }
  fields_.push_back(std::make_unique<Field>());
  Field& f = *fields_.back();
  f.name = name;
  f.components = components;
  f.range = range;
  return f;
}

Field* FieldStore::find(const std::string& name) {
  for (auto& f : fields_)
    if (f->name == name) return f.get();
  return nullptr;
}

const Field* FieldStore::find(const std::string& name) const {
  for (auto& f : fields_)
    if (f->name == name) return f.get();
  return nullptr;
}

template <int D>
void ParticleSet<D>::add(const Vec<D>& pos, const Vec<D>& vel, double rho, double m,
                         ParticleKind k, std::uint64_t ident) {
  const bool moving = k == ParticleKind::fluid;
  if (moving && nFixed() != 0)
    throw std::logic_error("moving particles must be added before fixed ones");
  for (int a = 0; a < D; ++a) {
    position.push_back(pos[a]);
    velocity.push_back(vel[a]);
  }
  density.push_back(rho);
  mass.push_back(m);
  kind.push_back(static_cast<std::uint8_t>(k));
  id.push_back(ident);
  if (moving) ++n_moving;
}

template <int D>
void ParticleSet<D>::resizeFields() {
  for (auto& f : fields.all()) {
    const std::size_t n = f->range == Field::Range::all      ? size()
                          : f->range == Field::Range::moving ? n_moving
                                                             : nFixed();
    f->data.assign(n * f->components, 0.0);
  }
}

template <int D>
void ParticleSet<D>::remapMoving(const ParticleRemap& m) {
  if (m.old_size != size() || m.old_moving != n_moving) throw std::logic_error("ParticleRemap made for another particle set");
  if (n_ghost_moving + n_ghost_fixed != 0) throw std::logic_error("ParticleRemap of a particle set with ghosts");
  std::size_t released = 0;
  for (Index s : m.source)
    if (s >= n_moving) ++released;
  if (released != m.released_ids.size()) throw std::logic_error("ParticleRemap: one id per released particle");
  m.apply(position, D, Field::Range::all);
  m.apply(velocity, D, Field::Range::all);
  m.apply(density, 1, Field::Range::all);
  m.apply(mass, 1, Field::Range::all);
  m.apply(kind, 1, Field::Range::all);
  m.apply(id, 1, Field::Range::all);
  for (auto& f : fields.all()) m.apply(f->data, f->components, f->range);
  std::size_t r = 0;
  for (std::size_t i = 0; i < m.newMoving(); ++i)
    if (m.source[i] >= m.old_moving) {
      kind[i] = static_cast<std::uint8_t>(ParticleKind::fluid);
      id[i] = m.released_ids[r++];
    }
  n_moving = m.newMoving();
}

template struct ParticleSet<2>;
template struct ParticleSet<3>;

}  // namespace vesph
