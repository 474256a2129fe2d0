#pragma once
// Cell-linked-list Verlet neighbour lists with a skin, and periodic axes (minimum image).
//
// The list holds every pair closer than cutoff + skin at build time. It is rebuilt only
// when some moving particle has moved more than skin/2 since the last build: two particles
// then approach by less than the skin, so no pair inside the cutoff is ever missed, whatever
// positions the integrator's stages try (docs/architecture.md "Integrators": multi-stage methods move particles
// between right-hand-side evaluations). Building is O(N): particles are binned into cells
// at least cutoff + skin wide and only the 3^D surrounding cells are searched.
//
// The cell grid is laid over the whole domain (its geometry fixes the order in which
// neighbours are listed), but storage is allocated only for the block of cells the particles
// occupy at the build (the whole grid along periodic axes): a small drop in a huge domain
// costs memory in proportion to the drop, not to the domain (docs/architecture.md).
//
// Layout (compressed rows): for particle i, nbr[start[i] .. split[i]) are moving
// neighbours and nbr[split[i] .. start[i+1]) fixed ones. Fixed particles list only their
// moving neighbours (fixed-fixed pairs are never needed).
#include <array>
#include <cstddef>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

// The largest distance, along the domain's minimum image, between the positions now and
// reference of the first n particles (D values each), in parallel: how far a particle has moved
// since a neighbour list or a halo was built.
template <int D>
double largestDisplacement(const Domain<D>& domain, const double* now, const double* reference, std::size_t n);

template <int D>
class NeighbourList {
 public:
  // cutoff: kernel support radius; skin: extra search distance (>= 0).
  void configure(const Domain<D>& domain, double cutoff, double skin);

  // Whether fixed particles may move between builds (inflow buffers): their displacement then
  // counts as well. Off by default: walls never move and cost nothing in the check.
  void trackFixed(bool on) {
    track_fixed_ = on;
    valid_ = false;
  }

  // Rebuilds when needed (or when force is set, or the particle count changed).
  // Returns true when it rebuilt.
  bool update(const ParticleSet<D>& particles, bool force = false);

  double cutoff() const { return cutoff_; }
  double skin() const { return skin_; }
  const Domain<D>& domain() const { return domain_; }
  std::size_t builds() const { return builds_; }
  std::size_t maxCount() const { return max_count_; }
  std::size_t entries() const { return nbr.size(); }

  // fn(j) for every moving particle j closer than the cutoff to the point x, at the current
  // positions (for values at points that are not particles: Fang's image-wall points). Exact
  // between rebuilds: a particle within the cutoff now was within cutoff + skin/2 at the
  // build, so it is binned in one of the 3^D cells around x (cells are >= cutoff + skin wide).
  template <class Fn>
  void forMovingNear(const ParticleSet<D>& p, const Vec<D>& x, Fn&& fn) const {
    std::array<int, D> ci;
    for (int a = 0; a < D; ++a) ci[a] = cellCoord(a, x[a]);
    const double cut2 = cutoff_ * cutoff_;
    forCellsAround(ci, [&](std::size_t cell) {
      for (std::size_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
        const Index j = cell_items_[k];
        if (j >= p.n_moving) continue;
        Vec<D> r;
        for (int a = 0; a < D; ++a) r[a] = domain_.image(a, x[a] - p.position[D * j + a]);
        if (r.squaredNorm() < cut2) fn(j, r);
      }
    });
  }

  std::vector<std::size_t> start;  // [N+1]
  std::vector<std::size_t> split;  // [N]
  std::vector<Index> nbr;

 private:
  void build(const ParticleSet<D>& particles);
  // fn(cell) for the 3^D cells around cell coordinates ci (wrapped on periodic axes, clipped
  // on the others).
  template <class Fn>
  void forCellsAround(const std::array<int, D>& ci, Fn&& fn) const {
    constexpr int noffsets = D == 2 ? 9 : 27;
    for (int o = 0; o < noffsets; ++o) {
      int rem = o;
      std::size_t cell = 0, stride = 1;
      bool skip = false;
      for (int a = 0; a < D; ++a) {
        int cc = ci[a] + (rem % 3) - 1;
        rem /= 3;
        if (cc < 0 || cc >= ncell_[a]) {
          if (!domain_.periodic[a]) {
            skip = true;
            break;
          }
          cc = (cc + ncell_[a]) % ncell_[a];
        }
        // Cells outside the occupied block hold no particle.
        cc -= block_lo_[a];
        if (cc < 0 || cc >= block_n_[a]) {
          skip = true;
          break;
        }
        cell += stride * static_cast<std::size_t>(cc);
        stride *= static_cast<std::size_t>(block_n_[a]);
      }
      if (!skip) fn(cell);
    }
  }
  double maxDisplacement(const ParticleSet<D>& particles) const;
  int cellCoord(int a, double x) const;

  Domain<D> domain_;
  double cutoff_ = 0, skin_ = 0;
  std::array<int, D> ncell_{};     // cells of the grid over the domain
  std::array<int, D> block_lo_{};  // the occupied block: first cell and
  std::array<int, D> block_n_{};   // number of cells per axis (cell storage is for these only)
  std::array<double, D> cell_width_{};
  std::vector<std::size_t> cell_start_;
  std::vector<Index> cell_items_;
  std::vector<Index> cell_of_;
  std::vector<double> reference_;  // moving (or all, with track_fixed_) positions at the last build
  bool track_fixed_ = false;
  std::size_t built_for_ = 0, built_moving_ = 0;
  std::size_t builds_ = 0, max_count_ = 0;
  bool valid_ = false;
};

}  // namespace vesph
