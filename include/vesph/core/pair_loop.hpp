#pragma once
// The one neighbour loop of vesph (docs/architecture.md "Neighbour loop"): nothing else
// iterates a NeighbourList. For each particle it gathers the neighbours inside the kernel
// support into a per-thread scratch batch, evaluating the pair geometry and the kernel once,
// and hands the batch to a callback. OpenMP parallelises over particles; a callback writes
// only to its own particle i, so there are no races and no atomics. Users: the pair driver
// (which runs the effects' pair passes), the ISPH projection (src/isph) and the reference
// operators (core/operators.hpp). Nothing in core/ depends on the physics layer.
//
// Loops that keep per-candidate values in the neighbour list's own layout (the ISPH matrix
// assembly stores gradient coefficients and wall weights by list entry) visit the candidates
// of one particle through CandidatePairs instead of a gathered batch.
#include <omp.h>

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

// One neighbour j of particle i, with the pair geometry evaluated once per pass:
// rij = xi - xj (minimum image), r = |rij|, W = W(r,h), F = (dW/dr)/r, so that the kernel
// gradient with respect to xi is grad_i W_ij = F * rij. W is evaluated only in passes that
// ask for it (with_w); otherwise it is left unset.
template <int D>
struct Neighbour {
  Vec<D> rij;
  double r;
  double W;
  double F;
  Index j;
};

// Dummy-wall boxes with a wetted face ([[blocks]] wetted_face; vesph/boundary/dummy_walls.hpp,
// docs/theory.md §6.5). The field wetted_face (Field::Range::fixed) holds per fixed particle
// a + 1 for the axis a of the wetted face's normal (0: none) and the block's box lo[D], hi[D];
// which of the two faces along that axis is wetted does not enter the rule. A moving particle beyond the
// block's end faces - outside the box along another axis than the face's, on either side of the
// wetted plane - and a particle of that block are not a pair: the dummy layers mirror the fluid
// across the wetted face and mean nothing for fluid that is not over it, such as the extrudate
// past a die's lip (its end face is dry). Scenes without the field never test.
template <int D>
struct WettedFaces {
  static constexpr int kComponents = 1 + 2 * D;
  static constexpr const char* kField = "wetted_face";

  // The fixed particles' records (null when the scene has no wetted face).
  static const double* records(const ParticleSet<D>& p) {
    const Field* f = p.fields.find(kField);
    return f && !f->data.empty() ? f->data.data() : nullptr;
  }
  // Whether the point x lies beyond an end face of the block whose record is f: outside the
  // box along an axis other than the wetted face's. A point within the box's extent along those
  // axes is over the wetted face, or inside the wall, where the block still acts (no leak).
  static bool beyondEndFace(const double* f, const double* x) {
    const int a = static_cast<int>(f[0]) - 1;
    if (a < 0) return false;
    for (int b = 0; b < D; ++b)
      if (b != a && (x[b] < f[1 + b] || x[b] > f[1 + D + b])) return true;
    return false;
  }
};

template <int D>
class PairLoop {
 public:
  // Sizes the per-thread scratch for the current list (allocation happens here, never in
  // a loop).
  void prepare(const NeighbourList<D>& list) {
    const std::size_t threads = static_cast<std::size_t>(omp_get_max_threads());
    if (scratch_.size() < threads) scratch_.resize(threads);
    for (auto& s : scratch_)
      if (s.size() < list.maxCount()) s.resize(list.maxCount() + 16);
  }

  // fn(i, moving neighbours, fixed neighbours) for every moving particle i this process owns
  // (all of them in a serial run; a distributed run's ghosts are neighbours only), in parallel.
  // W is evaluated only with with_w. Returns the pairs handed out.
  template <class Fn>
  std::uint64_t forEachMoving(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                              const NeighbourList<D>& list, bool with_w, Fn&& fn) {
    prepare(list);
    return with_w ? forEachMovingWhere<true>(p, kernel, domain, list, fn)
                  : forEachMovingWhere<false>(p, kernel, domain, list, fn);
  }

  // As forEachMoving, for the moving particles i with wanted(i) only. The scratch must be
  // prepared for this list (prepare, or forEachMoving on it).
  template <bool WithW, class Fn, class Pred = bool (*)(Index)>
  std::uint64_t forEachMovingWhere(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                                   const NeighbourList<D>& list, Fn&& fn, Pred&& wanted = everyParticle) {
    const std::size_t n = p.ownedMoving();
    const double* wetted = WettedFaces<D>::records(p);
    std::uint64_t pairs = 0;
    kernel.visit([&](auto shape) {
#pragma omp parallel reduction(+ : pairs) if (n >= kParallelMinimum)
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = 0; i < n; ++i) {
          if (!wanted(static_cast<Index>(i))) continue;
          const std::size_t nm = gather<WithW>(shape, p, kernel, domain, list, i, list.start[i], list.split[i], buf);
          const std::size_t nf =
              wetted ? gather<WithW, Wetted::neighbour>(shape, p, kernel, domain, list, i, list.split[i], list.start[i + 1],
                                                        buf + nm, wetted)
                     : gather<WithW>(shape, p, kernel, domain, list, i, list.split[i], list.start[i + 1], buf + nm);
          pairs += nm + nf;
          fn(static_cast<Index>(i), std::span<const Neighbour<D>>(buf, nm), std::span<const Neighbour<D>>(buf + nm, nf));
        }
      }
    });
    return pairs;
  }

  // A pass over the fixed particles this process owns, each with its moving neighbours (W
  // evaluated): fn(i, span<const Neighbour<D>>) for i in [n_moving, ownedEnd()). The scratch
  // must be prepared.
  template <class Fn>
  void forEachFixed(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                    const NeighbourList<D>& list, Fn&& fn) {
    const std::size_t n0 = p.n_moving, N = p.ownedEnd();
    const double* wetted = WettedFaces<D>::records(p);
    kernel.visit([&](auto shape) {
#pragma omp parallel if (N - n0 >= kParallelMinimum)
      {
        Neighbour<D>* buf = scratch_[static_cast<std::size_t>(omp_get_thread_num())].data();
#pragma omp for schedule(static)
        for (std::size_t i = n0; i < N; ++i) {
          const std::size_t nm =
              wetted ? gather<true, Wetted::self>(shape, p, kernel, domain, list, i, list.start[i], list.split[i], buf, wetted)
                     : gather<true>(shape, p, kernel, domain, list, i, list.start[i], list.split[i], buf);
          fn(static_cast<Index>(i), std::span<const Neighbour<D>>(buf, nm));
        }
      }
    });
  }

 private:
  static constexpr bool everyParticle(Index) { return true; }

  // Which wetted-face record a gathered pair is tested against (WettedFaces): none; each
  // neighbour's (the fixed neighbours of a moving particle); the particle's own (the moving
  // neighbours of a wall particle).
  enum class Wetted { none, neighbour, self };

  template <bool WithW, Wetted Test = Wetted::none, class Shape>
  static std::size_t gather(Shape, const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain,
                            const NeighbourList<D>& list, std::size_t i, std::size_t k0, std::size_t k1,
                            Neighbour<D>* out, const double* wetted = nullptr) {
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
      if constexpr (Test == Wetted::neighbour) {
        if (WettedFaces<D>::beyondEndFace(wetted + WettedFaces<D>::kComponents * (j - p.n_moving), xi)) continue;
      } else if constexpr (Test == Wetted::self) {
        if (WettedFaces<D>::beyondEndFace(wetted + WettedFaces<D>::kComponents * (i - p.n_moving), x + D * j)) continue;
      }
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
};

// The candidates of one particle in the neighbour list's own layout (entries k of
// [list.start[i], list.start[i+1]), candidates out to the support plus the skin), for loops
// that store a value per list entry and read the lists of a particle's neighbours too (the
// ISPH pressure matrix). The pair selection is the gathered loop's: r < support, r > 0.
//   CandidatePairs<D> pairs(particles, kernel, domain);
//   kernel.visit([&](auto shape) { ... pairs.visit(shape, i, k0, k1, inside, outside) ... });
// inside(k, j, rij, W, F) for a candidate inside the support, outside(k) otherwise.
template <int D>
class CandidatePairs {
 public:
  CandidatePairs(const ParticleSet<D>& p, const Kernel& kernel, const Domain<D>& domain, const NeighbourList<D>& list)
      : x_(p.position.data()),
        wetted_(WettedFaces<D>::records(p)),
        n_moving_(p.n_moving),
        nbr_(list.nbr.data()),
        domain_(&domain),
        cut2_(kernel.supportRadius() * kernel.supportRadius()),
        inv_h_(1.0 / kernel.h),
        w_scale_(kernel.w_scale),
        f_scale_(kernel.dw_scale / kernel.h) {}  // = the gathered loop's scale up to one rounding

  // The geometry of the pair (i, j); false outside the support (rij, W, F then unset).
  template <class Shape>
  bool operator()(Shape, std::size_t i, std::size_t j, Vec<D>& rij, double& W, double& F) const {
    double r2 = 0;
    for (int a = 0; a < D; ++a) {
      rij[a] = domain_->image(a, x_[D * i + a] - x_[D * j + a]);
      r2 += rij[a] * rij[a];
    }
    if (r2 >= cut2_ || r2 == 0.0) return false;
    if (wetted_ && (i < n_moving_) != (j < n_moving_)) {
      const std::size_t wall = i < n_moving_ ? j : i, moving = i < n_moving_ ? i : j;
      if (WettedFaces<D>::beyondEndFace(wetted_ + WettedFaces<D>::kComponents * (wall - n_moving_), x_ + D * moving))
        return false;
    }
    const double q = std::sqrt(r2) * inv_h_;
    W = w_scale_ * Shape::f(q);
    F = f_scale_ * Shape::df_over_q(q);
    return true;
  }

  // Entries [k0, k1) of particle i in list order.
  template <class Shape, class Inside, class Outside>
  void visit(Shape shape, std::size_t i, std::size_t k0, std::size_t k1, Inside&& inside, Outside&& outside) const {
    Vec<D> rij;
    double W, F;
    for (std::size_t k = k0; k < k1; ++k) {
      const std::size_t j = nbr_[k];
      if ((*this)(shape, i, j, rij, W, F))
        inside(k, j, rij, W, F);
      else
        outside(k);
    }
  }
  template <class Shape, class Inside>
  void visit(Shape shape, std::size_t i, std::size_t k0, std::size_t k1, Inside&& inside) const {
    visit(shape, i, k0, k1, inside, [](std::size_t) {});
  }

 private:
  const double* x_;
  const double* wetted_;  // WettedFaces records, or null
  std::size_t n_moving_;
  const Index* nbr_;
  const Domain<D>* domain_;
  double cut2_, inv_h_, w_scale_, f_scale_;
};

}  // namespace vesph
