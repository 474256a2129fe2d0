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

template struct ParticleSet<2>;
template struct ParticleSet<3>;

}  // namespace vesph
