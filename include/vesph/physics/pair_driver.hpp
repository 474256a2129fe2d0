#pragma once
// The one place that loops over neighbours (DESIGN.md "Style": a term never iterates
// neighbours itself). For each particle it gathers the neighbours inside the kernel support
// into a per-thread scratch batch, evaluating the pair geometry and the kernel once, and
// hands the batch to every pair effect of the pass. OpenMP parallelises over particles;
// every effect writes only to its own particle i, so there are no races and no atomics.
#include <omp.h>

#include <cstdint>
#include <span>
#include <vector>

#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
class PairDriver {
 public:
  // Sizes the per-thread scratch for the current list (allocation happens here, never in
  // a pass).
  void prepare(const NeighbourList<D>& list) {
    const std::size_t threads = static_cast<std::size_t>(omp_get_max_threads());
    if (scratch_.size() < threads) scratch_.resize(threads);
    for (auto& s : scratch_)
      if (s.size() < list.maxCount()) s.resize(list.maxCount() + 16);
  }

  // One pair pass over the moving particles with the given pair effects.
  void run(const RhsContext<D>& ctx, const NeighbourList<D>& list,
           std::span<Effect<D>* const> effects) {
    if (effects.empty()) return;
    const std::size_t n = ctx.particles.n_moving;
    std::uint64_t pairs = 0;
    ctx.kernel.visit([&](auto shape) {
#pragma omp parallel reduction(+ : pairs)
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
          const std::size_t nm = gather(shape, ctx, list, i, list.start[i], list.split[i], buf);
          const std::size_t nf = gather(shape, ctx, list, i, list.split[i], list.start[i + 1], buf + nm);
          pairs += nm + nf;
          const std::span<const Neighbour<D>> moving(buf, nm), fixed(buf + nm, nf);
          for (Effect<D>* e : effects) e->interact(ctx, static_cast<Index>(i), moving, fixed);
        }
      }
    });
    pairs_ += pairs;
  }

  // A pass over the fixed particles, each with its moving neighbours:
  // fn(i, span<const Neighbour<D>>) for i in [n_moving, N).
  template <class Fn>
  void runFixed(const RhsContext<D>& ctx, const NeighbourList<D>& list, Fn&& fn) {
    const std::size_t n0 = ctx.particles.n_moving, N = ctx.particles.size();
    ctx.kernel.visit([&](auto shape) {
#pragma omp parallel
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = n0; i < N; ++i) {
          const std::size_t nm = gather(shape, ctx, list, i, list.start[i], list.split[i], buf);
          fn(static_cast<Index>(i), std::span<const Neighbour<D>>(buf, nm));
        }
      }
    });
  }

  // Directed pairs inside the support handed to pair passes so far (for benchmarks).
  std::uint64_t pairsEvaluated() const { return pairs_; }

 private:
  template <class Shape>
  static std::size_t gather(Shape, const RhsContext<D>& ctx, const NeighbourList<D>& list,
                            std::size_t i, std::size_t k0, std::size_t k1, Neighbour<D>* out) {
    const double* x = ctx.particles.position.data();
    const double h = ctx.kernel.h, inv_h = 1.0 / h;
    const double cut2 = ctx.kernel.supportRadius() * ctx.kernel.supportRadius();
    const double ws = ctx.kernel.w_scale, dws = ctx.kernel.dw_scale;
    std::size_t c = 0;
    for (std::size_t k = k0; k < k1; ++k) {
      const Index j = list.nbr[k];
      Vec<D> d;
      for (int a = 0; a < D; ++a) d[a] = ctx.domain.image(a, x[D * i + a] - x[D * j + a]);
      const double r2 = d.squaredNorm();
      if (r2 >= cut2 || r2 == 0.0) continue;
      const double r = std::sqrt(r2), q = r * inv_h;
      Neighbour<D>& nb = out[c++];
      nb.rij = d;
      nb.r = r;
      nb.W = ws * Shape::f(q);
      nb.F = dws * Shape::df(q) / r;
      nb.j = j;
    }
    return c;
  }

  std::vector<std::vector<Neighbour<D>>> scratch_;
  std::uint64_t pairs_ = 0;
};

}  // namespace vesph
