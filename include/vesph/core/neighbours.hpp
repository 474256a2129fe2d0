#pragma once
// Cell-linked-list Verlet neighbour lists with a skin, and periodic axes (minimum image).
//
// The list holds every pair closer than cutoff + skin at build time. It is rebuilt only
// when some moving particle has moved more than skin/2 since the last build: two particles
// then approach by less than the skin, so no pair inside the cutoff is ever missed, whatever
// positions the integrator's stages try (DESIGN.md: multi-stage methods move particles
// between right-hand-side evaluations). Building is O(N): particles are binned into cells
// at least cutoff + skin wide and only the 3^D surrounding cells are searched.
//
// Layout (compressed rows): for particle i, nbr[start[i] .. split[i]) are moving
// neighbours and nbr[split[i] .. start[i+1]) fixed ones. Fixed particles list only their
// moving neighbours (fixed-fixed pairs are never needed).
#include <cstddef>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

template <int D>
class NeighbourList {
 public:
  // cutoff: kernel support radius; skin: extra search distance (>= 0).
  void configure(const Domain<D>& domain, double cutoff, double skin);

  // Rebuilds when needed (or when force is set, or the particle count changed).
  // Returns true when it rebuilt.
  bool update(const ParticleSet<D>& particles, bool force = false);

  double cutoff() const { return cutoff_; }
  double skin() const { return skin_; }
  const Domain<D>& domain() const { return domain_; }
  std::size_t builds() const { return builds_; }
  std::size_t maxCount() const { return max_count_; }
  std::size_t entries() const { return nbr.size(); }

  std::vector<std::size_t> start;  // [N+1]
  std::vector<std::size_t> split;  // [N]
  std::vector<Index> nbr;

 private:
  void build(const ParticleSet<D>& particles);
  double maxDisplacement(const ParticleSet<D>& particles) const;
  int cellCoord(int a, double x) const;

  Domain<D> domain_;
  double cutoff_ = 0, skin_ = 0;
  std::array<int, D> ncell_{};
  std::array<double, D> cell_width_{};
  std::vector<std::size_t> cell_start_;
  std::vector<Index> cell_items_;
  std::vector<Index> cell_of_;
  std::vector<double> reference_;  // moving positions at the last build
  std::size_t built_for_ = 0, built_moving_ = 0;
  std::size_t builds_ = 0, max_count_ = 0;
  bool valid_ = false;
};

}  // namespace vesph
