#pragma once
// The particles partitioned in space, one part per rank (docs/architecture.md "Distributed
// runs"): Zoltan's recursive coordinate bisection (Berger & Bokhari 1987; Zoltan user guide,
// "RCB"), which cuts the domain into axis-aligned boxes of equal weight. The boxes, not the
// particles, define ownership between repartitions: a particle belongs to the rank whose box
// holds it, and a halo is every particle within a radius of another rank's box
// (parallel/particle_exchange.hpp). The cuts are kept, so that the next partition moves them
// (RCB_REUSE) instead of starting afresh, and few particles change owner.
#include <memory>
#include <span>
#include <vector>

#include "vesph/core/domain.hpp"
#include "vesph/parallel/communicator.hpp"

struct Zoltan_Struct;

namespace vesph {

// An axis-aligned box [lo, hi] (a rank's part of the domain).
template <int D>
struct Box {
  Vec<D> lo, hi;
};

// The distance from x to the box along the domain's minimum image (periodic axes wrap).
template <int D>
double distanceToBox(const Domain<D>& domain, const double* x, const Box<D>& box);
// The distance between two boxes (zero when they touch or overlap), periodic axes wrapped.
template <int D>
double distanceBetweenBoxes(const Domain<D>& domain, const Box<D>& a, const Box<D>& b);

template <int D>
class SpacePartition {
 public:
  // imbalance_tolerance: the largest part's weight over the mean that RCB may leave (Zoltan's
  // IMBALANCE_TOL, >= 1).
  SpacePartition(const Communicator& comm, const Domain<D>& domain, double imbalance_tolerance = 1.02);
  ~SpacePartition();
  SpacePartition(const SpacePartition&) = delete;
  SpacePartition& operator=(const SpacePartition&) = delete;

  // Partitions the particles this rank holds (positions: n * D values, weights: n values > 0,
  // the cost of each particle) together with every other rank's, and returns the rank each of
  // this rank's particles goes to. Updates boxes(). Collective.
  std::vector<int> partition(std::span<const double> positions, std::span<const double> weights);

  // The rank whose box holds x (the last partition's cuts). Not collective.
  int owner(const double* x) const;

  // Every rank's box, clipped to the domain along its periodic axes (a part at the edge of
  // the domain is otherwise unbounded there: RCB's outer boxes reach to infinity). Empty
  // before the first partition.
  const std::vector<Box<D>>& boxes() const { return boxes_; }
  std::size_t partitions() const { return partitions_; }

 private:
  Communicator comm_;
  Domain<D> domain_;
  Zoltan_Struct* zz_ = nullptr;
  std::vector<Box<D>> boxes_;
  std::size_t partitions_ = 0;
};

}  // namespace vesph
