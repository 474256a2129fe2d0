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

  // One pair pass over the moving particles with the given pair effects. Effects that
  // prepare per-particle values (Effect::prepares) get their prepare() over all particles
  // first, effects that ask for a second sweep (Effect::secondSweep) their interactAgain()
  // after; without either the pass runs no extra code.
  void run(const RhsContext<D>& ctx, const NeighbourList<D>& list,
           std::span<Effect<D>* const> effects) {
    if (effects.empty()) return;
    bool need_w = false, need_prepare = false;
    for (Effect<D>* e : effects) {
      need_w = need_w || e->needsKernelValue();
      need_prepare = need_prepare || e->prepares();
    }
    if (need_prepare) prepareParticles(ctx, effects);
    pairs_ += forEachMoving(ctx.particles, ctx.kernel, ctx.domain, list, need_w,
                            [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                              for (Effect<D>* e : effects) e->interact(ctx, i, moving, fixed);
                            });
    // The second sweep gathers the neighbours only of the particles some effect asks for
    // (Effect::sweepAgain): near a free surface, a few per cent of them.
    // The scratch is sized for this list already (forEachMoving above).
    again_.clear();
    for (Effect<D>* e : effects)
      if (e->secondSweep()) again_.push_back(e);
    if (again_.empty()) return;
    auto wanted = [&](Index i) {
      for (Effect<D>* e : again_)
        if (e->sweepAgain(ctx, i)) return true;
      return false;
    };
    pairs_ += loop<false>(ctx.particles, ctx.kernel, ctx.domain, list,
                          [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                            for (Effect<D>* e : again_)
                              if (e->sweepAgain(ctx, i)) e->interactAgain(ctx, i, moving, fixed);
                          },
                          wanted);
  }

  // The neighbour loop itself: fn(i, moving neighbours, fixed neighbours) for every moving
  // particle i, in parallel. W is evaluated only with with_w. Returns the pairs handed out.
  template <class Fn>
  std::uint64_t forEachMoving(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                              const NeighbourList<D>& list, bool with_w, Fn&& fn) {
    prepare(list);
    return with_w ? loop<true>(p, kernel, domain, list, fn) : loop<false>(p, kernel, domain, list, fn);
  }

  // A pass over the fixed particles, each with its moving neighbours:
  // fn(i, span<const Neighbour<D>>) for i in [n_moving, N).
  template <class Fn>
  void runFixed(const RhsContext<D>& ctx, const NeighbourList<D>& list, Fn&& fn) {
    const ParticleSet<D>& p = ctx.particles;
    const std::size_t n0 = p.n_moving, N = p.size();
    ctx.kernel.visit([&](auto shape) {
#pragma omp parallel if (N - n0 >= kParallelMinimum)
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = n0; i < N; ++i) {
          const std::size_t nm = gather<true>(shape, p, ctx.kernel, ctx.domain, list, i, list.start[i], list.split[i], buf);
          fn(static_cast<Index>(i), std::span<const Neighbour<D>>(buf, nm));
        }
      }
    });
  }

  // Directed pairs inside the support handed to pair passes so far (for benchmarks).
  std::uint64_t pairsEvaluated() const { return pairs_; }

 private:
  // Effect::prepare over all particles [0, N), one contiguous range per thread.
  static void prepareParticles(const RhsContext<D>& ctx, std::span<Effect<D>* const> effects) {
    const std::size_t N = ctx.particles.size();
#pragma omp parallel if (N >= kParallelMinimum)
    {
      const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
      const std::size_t t = static_cast<std::size_t>(omp_get_thread_num());
      const std::size_t b = N * t / nt, e = N * (t + 1) / nt;
      for (Effect<D>* eff : effects)
        if (eff->prepares()) eff->prepare(ctx, b, e);
    }
  }

  static constexpr bool everyParticle(Index) { return true; }

  template <bool WithW, class Fn, class Pred = bool (*)(Index)>
  std::uint64_t loop(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                     const NeighbourList<D>& list, Fn&& fn, Pred&& wanted = everyParticle) {
    const std::size_t n = p.n_moving;
    std::uint64_t pairs = 0;
    kernel.visit([&](auto shape) {
#pragma omp parallel reduction(+ : pairs) if (n >= kParallelMinimum)
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
          if (!wanted(static_cast<Index>(i))) continue;
          const std::size_t nm = gather<WithW>(shape, p, kernel, domain, list, i, list.start[i], list.split[i], buf);
          const std::size_t nf = gather<WithW>(shape, p, kernel, domain, list, i, list.split[i], list.start[i + 1], buf + nm);
          pairs += nm + nf;
          fn(static_cast<Index>(i), std::span<const Neighbour<D>>(buf, nm), std::span<const Neighbour<D>>(buf + nm, nf));
        }
      }
    });
    return pairs;
  }

  template <bool WithW, class Shape>
  static std::size_t gather(Shape, const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                            const NeighbourList<D>& list, std::size_t i, std::size_t k0, std::size_t k1,
                            Neighbour<D>* out) {
    // Everything the loop reads is copied into locals first: the compiler cannot otherwise
    // prove that the stores into `out` leave them unchanged, and reloads them every pair.
    const double* __restrict x = p.position.data();
    const Index* __restrict nbr = list.nbr.data();
    const double inv_h = 1.0 / kernel.h;
    const double cut2 = kernel.supportRadius() * kernel.supportRadius();
    // F = (dW/dr)/r = (sigma/h^(D+1)) f'(q)/(q h)
    const double ws = kernel.w_scale, fs = kernel.dw_scale * inv_h;
    double period[D], half[D], xi[D];
    for (int a = 0; a < D; ++a) {
      period[a] = domain.periodic[a] ? domain.length(a) : 0.0;
      half[a] = domain.periodic[a] ? 0.5 * period[a] : 1e300;
      xi[a] = x[D * i + a];
    }
    std::size_t c = 0;
    for (std::size_t k = k0; k < k1; ++k) {
      const Index j = nbr[k];
      double d[D], r2 = 0;
      for (int a = 0; a < D; ++a) {
        double da = xi[a] - x[D * j + a];
        da = da > half[a] ? da - period[a] : (da < -half[a] ? da + period[a] : da);
        d[a] = da;
        r2 += da * da;
      }
      if (r2 >= cut2 || r2 == 0.0) continue;
      const double r = std::sqrt(r2), q = r * inv_h;
      Neighbour<D>& nb = out[c++];
      for (int a = 0; a < D; ++a) nb.rij[a] = d[a];
      nb.r = r;
      if constexpr (WithW) nb.W = ws * Shape::f(q);
      nb.F = fs * Shape::df_over_q(q);
      nb.j = j;
    }
    return c;
  }

  std::vector<std::vector<Neighbour<D>>> scratch_;
  std::vector<Effect<D>*> again_;
  std::uint64_t pairs_ = 0;
};

}  // namespace vesph
