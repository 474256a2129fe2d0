#pragma once
// The pair driver runs the pair effects of a pass (docs/architecture.md "Neighbour loop": a
// term never iterates neighbours itself). For each moving particle the neighbour loop
// (core/pair_loop.hpp) gathers the neighbours inside the kernel support, and the driver hands
// the batch to every pair effect of the pass; every effect writes only to its own particle i.
#include <cstdint>
#include <span>
#include <vector>

#include "vesph/core/pair_loop.hpp"
#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
class PairDriver {
 public:
  // Sizes the loop's per-thread scratch for the current list (allocation happens here, never
  // in a pass).
  void prepare(const NeighbourList<D>& list) { loop_.prepare(list); }

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
    pairs_ += loop_.forEachMoving(ctx.particles, ctx.kernel, ctx.domain, list, need_w,
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
    pairs_ += loop_.template forEachMovingWhere<false>(
        ctx.particles, ctx.kernel, ctx.domain, list,
        [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
          for (Effect<D>* e : again_)
            if (e->sweepAgain(ctx, i)) e->interactAgain(ctx, i, moving, fixed);
        },
        wanted);
  }

  // The neighbour loop for passes that are not effects (the ISPH projection):
  // fn(i, moving neighbours, fixed neighbours) for every moving particle i, in parallel. W is
  // evaluated only with with_w. Returns the pairs handed out.
  template <class Fn>
  std::uint64_t forEachMoving(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                              const NeighbourList<D>& list, bool with_w, Fn&& fn) {
    return loop_.forEachMoving(p, kernel, domain, list, with_w, fn);
  }

  // A pass over the fixed particles, each with its moving neighbours:
  // fn(i, span<const Neighbour<D>>) for i in [n_moving, N).
  template <class Fn>
  void runFixed(const RhsContext<D>& ctx, const NeighbourList<D>& list, Fn&& fn) {
    loop_.forEachFixed(ctx.particles, ctx.kernel, ctx.domain, list, fn);
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

  PairLoop<D> loop_;
  std::vector<Effect<D>*> again_;
  std::uint64_t pairs_ = 0;
};

}  // namespace vesph
