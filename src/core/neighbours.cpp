#include "vesph/core/neighbours.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

namespace vesph {

template <int D>
void NeighbourList<D>::configure(const Domain<D>& domain, double cutoff, double skin) {
  domain_ = domain;
  cutoff_ = cutoff;
  skin_ = skin;
  const double reach = cutoff + skin;
  for (int a = 0; a < D; ++a) {
    const double L = domain.length(a);
    if (!(L > 0)) throw InputError("domain: max must exceed min along every axis");
    int n = domain.periodic[a] ? static_cast<int>(std::floor(L / reach))
                               : std::max(1, static_cast<int>(std::ceil(L / reach)));
    if (domain.periodic[a] && n < 3) {
      std::ostringstream os;
      os << "domain: the periodic length along axis " << a << " (" << L
         << " m) must be at least 3 times the neighbour search radius (kernel support + skin = "
         << reach << " m), i.e. at least " << 3 * reach << " m";
      throw InputError(os.str());
    }
    // Cap the grid so that a huge, mostly empty domain does not allocate billions of cells.
    n = std::min(n, 1 << 20);
    ncell_[a] = n;
    cell_width_[a] = domain.periodic[a] ? L / n : std::max(reach, L / n);
  }
  valid_ = false;
}

template <int D>
int NeighbourList<D>::cellCoord(int a, double x) const {
  const double y = domain_.wrap(a, x);
  int c = static_cast<int>(std::floor((y - domain_.lo[a]) / cell_width_[a]));
  return std::clamp(c, 0, ncell_[a] - 1);
}

template <int D>
double largestDisplacement(const Domain<D>& domain, const double* now, const double* reference, std::size_t n) {
  double m2 = 0;
#pragma omp parallel for reduction(max : m2) schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    double d2 = 0;
    for (int a = 0; a < D; ++a) {
      const double d = domain.image(a, now[D * i + a] - reference[D * i + a]);
      d2 += d * d;
    }
    m2 = std::max(m2, d2);
  }
  return std::sqrt(m2);
}

template <int D>
double NeighbourList<D>::maxDisplacement(const ParticleSet<D>& p) const {
  return largestDisplacement(domain_, p.position.data(), reference_.data(), track_fixed_ ? p.size() : p.n_moving);
}

template <int D>
bool NeighbourList<D>::update(const ParticleSet<D>& p, bool force) {
  const bool changed = !valid_ || p.size() != built_for_ || p.n_moving != built_moving_;
  if (!force && !changed && maxDisplacement(p) <= 0.5 * skin_) return false;
  build(p);
  return true;
}

template <int D>
void NeighbourList<D>::build(const ParticleSet<D>& p) {
  const std::size_t N = p.size(), nm = p.n_moving;

  // The block of grid cells the particles occupy (non-finite positions are reported below).
  std::array<int, D> cmin, cmax;
  for (int a = 0; a < D; ++a) {
    cmin[a] = domain_.periodic[a] ? 0 : ncell_[a] - 1;
    cmax[a] = domain_.periodic[a] ? ncell_[a] - 1 : 0;
  }
  if (N == 0) cmin = cmax;
  for (int a = 0; a < D; ++a) {
    if (domain_.periodic[a]) continue;
    int lo = cmin[a], hi = cmax[a];
#pragma omp parallel for schedule(static) if (N >= kParallelMinimum) reduction(min : lo) reduction(max : hi)
    for (std::size_t i = 0; i < N; ++i) {
      const double x = p.position[D * i + a];
      if (!std::isfinite(x)) continue;
      const int c = cellCoord(a, x);
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    cmin[a] = lo;
    cmax[a] = std::max(lo, hi);
  }
  std::size_t ncells = 1;
  for (int a = 0; a < D; ++a) {
    block_lo_[a] = cmin[a];
    block_n_[a] = cmax[a] - cmin[a] + 1;
    ncells *= static_cast<std::size_t>(block_n_[a]);
  }
  // Cells are 8 bytes each; a block far larger than the particle count (particles scattered over
  // a huge domain) is refused with its size rather than ending in std::bad_alloc.
  const std::size_t max_cells = std::max<std::size_t>(std::size_t{1} << 24, 64 * N);
  if (ncells > max_cells) {
    std::ostringstream os;
    os << "the neighbour search's cell grid over the particles' extent would need " << ncells << " cells ("
       << static_cast<double>(ncells) * 8 / (1 << 30) << " GiB) for " << N
       << " particles: the particles are spread over a region far larger than the kernel support";
    throw NumericalFailure(os.str());
  }

  // Bin particles: cell of each particle in parallel, then a counting sort, stable in
  // particle index.
  cell_of_.resize(N);
  cell_start_.assign(ncells + 1, 0);
  long bad = -1;
#pragma omp parallel for schedule(static) if (N >= kParallelMinimum) reduction(max : bad)
  for (std::size_t i = 0; i < N; ++i) {
    std::size_t c = 0;
    for (int a = D - 1; a >= 0; --a) {
      const double x = p.position[D * i + a];
      if (!std::isfinite(x)) bad = std::max(bad, static_cast<long>(i));
      c = c * block_n_[a] + (std::isfinite(x) ? cellCoord(a, x) - block_lo_[a] : 0);
    }
    cell_of_[i] = static_cast<Index>(c);
  }
  if (bad >= 0) throw NumericalFailure("non-finite position of particle id " + std::to_string(p.id[bad]));
  // Counting sort of the particles by bin: start[b] .. start[b + 1] index items, the particles
  // of bin b in increasing order (start holds nbins + 1 zeros on entry).
  auto binParticles = [N](const auto& bin_of, std::size_t nbins, std::vector<std::size_t>& start,
                          std::vector<Index>& items) {
    for (std::size_t i = 0; i < N; ++i) ++start[bin_of[i] + 1];
    for (std::size_t b = 0; b < nbins; ++b) start[b + 1] += start[b];
    items.resize(N);
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < N; ++i) items[fill[bin_of[i]]++] = static_cast<Index>(i);
  };
  binParticles(cell_of_, ncells, cell_start_, cell_items_);

  const double reach2 = (cutoff_ + skin_) * (cutoff_ + skin_);
  // fn(j) for the particles j != i of items[begin, end) within reach of x_i.
  auto testBin = [&](std::size_t i, const double* xi, const std::vector<Index>& items, std::size_t begin,
                     std::size_t end, auto&& fn) {
    for (std::size_t k = begin; k < end; ++k) {
      const Index j = items[k];
      if (j == i) continue;
      double r2 = 0;
      for (int a = 0; a < D; ++a) {
        const double d = domain_.image(a, xi[a] - p.position[D * j + a]);
        r2 += d * d;
      }
      if (r2 < reach2) fn(j);
    }
  };
  // Visits every candidate j of particle i; fn(j) for those within reach.
  auto forCandidates = [&](std::size_t i, auto&& fn) {
    std::array<int, D> ci;
    std::size_t c = cell_of_[i];
    for (int a = 0; a < D; ++a) {
      ci[a] = static_cast<int>(c % block_n_[a]) + block_lo_[a];
      c /= block_n_[a];
    }
    const double* xi = &p.position[D * i];
    forCellsAround(ci, [&](std::size_t cell) { testBin(i, xi, cell_items_, cell_start_[cell], cell_start_[cell + 1], fn); });
  };

  // 3D: the cells above are at least one search radius wide, so the 27 around a particle hold
  // about 8 times the candidates that lie within reach (958 tested for 122 kept in the periodic
  // benchmark box, docs/performance.md "3D"). The list is filled from sub-cells instead: every
  // cell halved along each axis (sub-cell width >= reach/2), the 5^3 sub-cells around a
  // particle's own searched, 42 % fewer distance tests in that box. 2D keeps the 3^2 cells
  // (3 times the kept candidates there; its lists, hence its results, stay bit for bit).
  // The cells themselves stay, for the point queries of forEachCandidate.
  constexpr int sub = 2;  // sub-cells per cell and axis
  std::array<int, D> sub_n{};
  std::size_t nsub = 1;
  for (int a = 0; a < D; ++a) {
    sub_n[a] = sub * block_n_[a];
    nsub *= static_cast<std::size_t>(sub_n[a]);
  }
  const bool use_sub = D == 3 && nsub <= max_cells;
  std::vector<Index> sub_of, sub_items;
  std::vector<std::size_t> sub_start;
  if (use_sub) {
    sub_of.resize(N);
#pragma omp parallel for schedule(static) if (N >= kParallelMinimum)
    for (std::size_t i = 0; i < N; ++i) {
      std::size_t c = 0;
      for (int a = D - 1; a >= 0; --a) {
        // the cell of cellCoord, then the half of it the particle is in (clamped like the cell)
        const double u = (domain_.wrap(a, p.position[D * i + a]) - domain_.lo[a]) / cell_width_[a];
        const int cell = std::clamp(static_cast<int>(std::floor(u)), 0, ncell_[a] - 1);
        const int half = std::clamp(static_cast<int>(std::floor(sub * (u - cell))), 0, sub - 1);
        c = c * sub_n[a] + static_cast<std::size_t>(sub * (cell - block_lo_[a]) + half);
      }
      sub_of[i] = static_cast<Index>(c);
    }
    sub_start.assign(nsub + 1, 0);
    binParticles(sub_of, nsub, sub_start, sub_items);
  }
  // As forCandidates, over the 5^D sub-cells around particle i's (wrapped on periodic axes,
  // where a cell count of at least 3 makes at least 6 sub-cells, so none is visited twice).
  auto forSubCandidates = [&](std::size_t i, auto&& fn) {
    std::array<int, D> si;
    std::size_t c = sub_of[i];
    for (int a = 0; a < D; ++a) {
      si[a] = static_cast<int>(c % sub_n[a]) + sub * block_lo_[a];
      c /= sub_n[a];
    }
    const double* xi = &p.position[D * i];
    constexpr int width = 2 * sub + 1, noffsets = D == 2 ? width * width : width * width * width;
    for (int o = 0; o < noffsets; ++o) {
      int rem = o;
      std::size_t cell = 0, stride = 1;
      bool skip = false;
      for (int a = 0; a < D; ++a) {
        int cc = si[a] + (rem % width) - sub;
        rem /= width;
        const int total = sub * ncell_[a];
        if (cc < 0 || cc >= total) {
          if (!domain_.periodic[a]) {
            skip = true;
            break;
          }
          cc = (cc + total) % total;
        }
        cc -= sub * block_lo_[a];
        if (cc < 0 || cc >= sub_n[a]) {
          skip = true;
          break;
        }
        cell += stride * static_cast<std::size_t>(cc);
        stride *= static_cast<std::size_t>(sub_n[a]);
      }
      if (!skip) testBin(i, xi, sub_items, sub_start[cell], sub_start[cell + 1], fn);
    }
  };
  auto forListCandidates = [&](std::size_t i, auto&& fn) {
    if (use_sub) forSubCandidates(i, fn);
    else forCandidates(i, fn);
  };

  // Pass 1: count; pass 2: fill (moving neighbours first, then fixed).
  std::vector<std::size_t> count_moving(N), count_fixed(N);
#pragma omp parallel for schedule(dynamic, 256) if (N >= kParallelMinimum)
  for (std::size_t i = 0; i < N; ++i) {
    std::size_t cm = 0, cf = 0;
    const bool fixed_i = i >= nm;
    forListCandidates(i, [&](Index j) {
      if (j < nm) ++cm;
      else if (!fixed_i) ++cf;
    });
    count_moving[i] = cm;
    count_fixed[i] = cf;
  }
  start.resize(N + 1);
  split.resize(N);
  start[0] = 0;
  max_count_ = 0;
  for (std::size_t i = 0; i < N; ++i) {
    split[i] = start[i] + count_moving[i];
    start[i + 1] = split[i] + count_fixed[i];
    max_count_ = std::max(max_count_, count_moving[i] + count_fixed[i]);
  }
  nbr.resize(start[N]);
#pragma omp parallel for schedule(dynamic, 256) if (N >= kParallelMinimum)
  for (std::size_t i = 0; i < N; ++i) {
    std::size_t km = start[i], kf = split[i];
    const bool fixed_i = i >= nm;
    forListCandidates(i, [&](Index j) {
      if (j < nm) nbr[km++] = j;
      else if (!fixed_i) nbr[kf++] = j;
    });
  }

  reference_.assign(p.position.begin(), p.position.begin() + D * (track_fixed_ ? N : nm));
  built_for_ = N;
  built_moving_ = nm;
  valid_ = true;
  ++builds_;
}

template class NeighbourList<2>;
template class NeighbourList<3>;
template double largestDisplacement<2>(const Domain<2>&, const double*, const double*, std::size_t);
template double largestDisplacement<3>(const Domain<3>&, const double*, const double*, std::size_t);

}  // namespace vesph
