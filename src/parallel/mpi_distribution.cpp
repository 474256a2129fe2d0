#include "vesph/parallel/mpi_distribution.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "vesph/core/neighbours.hpp"
#include "vesph/parallel/particle_exchange.hpp"

namespace vesph {

namespace {

// Walls cost a process less than fluid: they take part in the wall-value pass only.
constexpr double kFixedParticleWeight = 0.25;

template <int D>
class MpiDistribution final : public ParticleDistribution<D> {
 public:
  MpiDistribution(const Domain<D>& domain, double cutoff, double skin, double tolerance, int halo_supports)
      : comm_(Communicator::world()), domain_(domain), partition_(comm_, domain), exchange_(comm_, domain),
        dealer_(comm_, domain), radius_(halo_supports * cutoff + skin), skin_(skin), tolerance_(tolerance) {
    if (halo_supports < 1) throw std::invalid_argument("a halo is at least one kernel support deep");
    if (!(skin > 0))
      throw std::invalid_argument("a distributed run needs a neighbour skin > 0 (neighbours.skin): the halo holds "
                                  "until the particles have moved half of it");
  }

  int rank() const override { return comm_.rank(); }
  int size() const override { return comm_.size(); }
  const void* communicator() const override { return &handle_; }

  void distribute(ParticleSet<D>& p) override {
    // Every process built the whole scene: each hands Zoltan a disjoint share (particle k to
    // process k mod size), then keeps the particles inside its box.
    std::vector<double> share_x, share_w;
    for (std::size_t i = static_cast<std::size_t>(rank()); i < p.size(); i += static_cast<std::size_t>(size())) {
      for (int a = 0; a < D; ++a) share_x.push_back(p.position[D * i + a]);
      share_w.push_back(i < p.n_moving ? 1.0 : kFixedParticleWeight);
    }
    partition_.partition(share_x, share_w);
    ++repartitions_;
    const std::uint64_t whole = p.size();
    std::vector<char> keep(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) keep[i] = partition_.owner(p.position.data() + D * i) == rank();
    exchange_.keepOnly(p, keep);
    if (comm_.sum(static_cast<std::uint64_t>(p.size())) != whole)
      throw std::logic_error("distribution: the shares do not add up to the scene");
    buildHalo(p);
  }

  void refreshState(ParticleSet<D>& p, std::span<Field* const> evolving) override {
    arrays_.clear();
    arrays_.push_back({p.position.data(), D, Field::Range::all});
    arrays_.push_back({p.velocity.data(), D, Field::Range::all});
    arrays_.push_back({p.density.data(), 1, Field::Range::all});
    for (Field* f : evolving) arrays_.push_back({f->data.data(), f->components, f->range});
    exchange_.refresh(arrays_);
  }

  void refreshFields(ParticleSet<D>& p) override {
    arrays_.clear();
    arrays_.push_back({p.velocity.data(), D, Field::Range::all});
    arrays_.push_back({p.density.data(), 1, Field::Range::all});
    for (const auto& f : p.fields.all())
      if (f->refreshed_in_halo) arrays_.push_back({f->data.data(), f->components, f->range});
    exchange_.refresh(arrays_);
  }

  void refreshArrays(std::span<const HaloArray> arrays) override { exchange_.refresh(arrays); }

  RedistributionNeed needsRedistribution(const ParticleSet<D>& p, double step_motion, bool changes_here) override {
    double moved = largestDisplacement(domain_, p.position.data(), reference_.data(), p.ownedMoving());
    const std::size_t owned_fixed = p.ownedEnd() - p.n_moving;
    if (owned_fixed)  // an inflow buffer moves (walls do not)
      moved = std::max(moved, largestDisplacement(domain_, p.position.data() + D * p.n_moving,
                                                  reference_.data() + D * p.ownedMoving(), owned_fixed));
    // A pair within the cutoff now was within cutoff + 2 d when the halo was built, d being the
    // larger of the two displacements: the halo (cutoff + skin) holds while d < skin / 2, and it
    // must hold until the next step has ended: twice the last step's motion is kept in reserve
    // (the speed may grow within the step). One reduction for both questions.
    double local[2] = {moved, changes_here ? 1.0 : 0.0}, global[2] = {0, 0};
    MPI_Allreduce(local, global, 2, MPI_DOUBLE, MPI_MAX, comm_.handle());
    RedistributionNeed need;
    need.particle_changes = global[1] > 0;
    need.redistribute = need.particle_changes || global[0] > 0.5 * skin_ - 2.0 * step_motion;
    return need;
  }

  void removeHalo(ParticleSet<D>& p) override { exchange_.removeHalo(p); }

  void redistribute(ParticleSet<D>& p) override {
    exchange_.removeHalo(p);
    std::vector<int> destination(p.size());
    if (loadImbalance(comm_, static_cast<double>(p.n_moving)) > tolerance_) {
      destination = partition_.partition(p.position, weights(p));
      ++repartitions_;
    } else {
      for (std::size_t i = 0; i < p.size(); ++i) destination[i] = partition_.owner(p.position.data() + D * i);
    }
    exchange_.migrate(p, destination);
    ++redistributions_;
    buildHalo(p);
  }

  ParticleSet<D> owned(const ParticleSet<D>& p) override {
    ParticleSet<D> copy;
    for (const auto& f : p.fields.all()) copy.fields.require(f->name, f->components, f->range).data = f->data;
    copy.position = p.position;
    copy.velocity = p.velocity;
    copy.density = p.density;
    copy.mass = p.mass;
    copy.kind = p.kind;
    copy.id = p.id;
    copy.n_moving = p.n_moving;
    std::vector<char> keep(p.size(), 1);
    std::fill(keep.begin() + static_cast<std::ptrdiff_t>(p.ownedMoving()), keep.begin() + static_cast<std::ptrdiff_t>(p.n_moving), 0);
    std::fill(keep.begin() + static_cast<std::ptrdiff_t>(p.ownedEnd()), keep.end(), 0);
    dealer_.keepOnly(copy, keep);
    return copy;
  }

  OutputShare<D> deal(ParticleSet<D> owned) override {
    // Blocks of the ids (the scene's ids are 0 .. N-1, moving ones first: each process then
    // holds one contiguous run of the file's rows, which it writes as one piece).
    std::uint64_t local_end = 0;
    for (std::uint64_t ident : owned.id) local_end = std::max(local_end, ident + 1);
    std::uint64_t id_end = 0;
    MPI_Allreduce(&local_end, &id_end, 1, MPI_UINT64_T, MPI_MAX, comm_.handle());
    const auto procs = static_cast<std::uint64_t>(size());
    std::vector<int> destination(owned.size());
    for (std::size_t i = 0; i < owned.size(); ++i)
      destination[i] = static_cast<int>(std::min(procs - 1, static_cast<std::uint64_t>(
                                                                (static_cast<unsigned __int128>(owned.id[i]) * procs) / id_end)));
    dealer_.migrate(owned, destination);
    sortById(owned);
    OutputShare<D> share;
    const std::uint64_t counts[2] = {owned.n_moving, owned.nFixed()};
    std::uint64_t offsets[2] = {0, 0}, totals[2] = {0, 0};
    MPI_Exscan(counts, offsets, 2, MPI_UINT64_T, MPI_SUM, comm_.handle());
    if (rank() == 0) offsets[0] = offsets[1] = 0;  // MPI_Exscan leaves rank 0's undefined
    MPI_Allreduce(counts, totals, 2, MPI_UINT64_T, MPI_SUM, comm_.handle());
    share.moving_offset = offsets[0];
    share.moving_total = totals[0];
    share.fixed_offset = offsets[1];
    share.fixed_total = totals[1];
    share.particles = std::move(owned);
    return share;
  }

  double sum(double local) override { return comm_.sum(local); }
  double max(double local) override { return comm_.max(local); }
  std::uint64_t sum(std::uint64_t local) override { return comm_.sum(local); }
  void sum(std::span<double> values) override {
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_SUM, comm_.handle());
  }
  void max(std::span<double> values) override {
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX, comm_.handle());
  }
  std::vector<double> allGather(const std::vector<double>& local) override {
    const int mine = static_cast<int>(local.size());
    std::vector<int> counts(static_cast<std::size_t>(size())), starts(static_cast<std::size_t>(size()), 0);
    MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm_.handle());
    for (std::size_t r = 1; r < counts.size(); ++r) starts[r] = starts[r - 1] + counts[r - 1];
    std::vector<double> all(static_cast<std::size_t>(starts.back() + counts.back()));
    MPI_Allgatherv(local.data(), mine, MPI_DOUBLE, all.data(), counts.data(), starts.data(), MPI_DOUBLE, comm_.handle());
    return all;
  }

  std::string firstMessage(const std::string& local) override {
    int mine = local.empty() ? size() : rank(), first = size();
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm_.handle());
    if (first == size()) return {};
    std::uint64_t length = local.size();
    MPI_Bcast(&length, 1, MPI_UINT64_T, first, comm_.handle());
    std::string out = rank() == first ? local : std::string(length, ' ');
    MPI_Bcast(out.data(), static_cast<int>(length), MPI_CHAR, first, comm_.handle());
    return out;
  }

  [[noreturn]] void abort(const std::string& message) override {
    std::fprintf(stderr, "vesph: error on process %d of %d: %s; every process stops\n", rank(), size(), message.c_str());
    std::fflush(stderr);
    MPI_Abort(comm_.handle(), 1);
    std::abort();  // MPI_Abort does not return
  }

  double imbalance() const override { return imbalance_; }
  std::uint64_t redistributions() const override { return redistributions_; }
  std::uint64_t repartitions() const override { return repartitions_; }

  DistributionCounters counters() override {
    const HaloCounters& h = exchange_.counters();
    DistributionCounters c;
    c.ghosts = comm_.sum(static_cast<std::uint64_t>(h.ghosts_received));
    c.neighbour_links = comm_.sum(static_cast<std::uint64_t>(h.neighbour_ranks));
    c.refreshes = h.refreshes;
    c.messages = comm_.sum(h.messages_sent);
    c.bytes = comm_.sum(h.bytes_sent);
    c.migrated = comm_.sum(h.particles_migrated);
    return c;
  }

 private:
  std::vector<double> weights(const ParticleSet<D>& p) const {
    std::vector<double> w(p.size(), kFixedParticleWeight);
    std::fill(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(p.n_moving), 1.0);
    return w;
  }

  void buildHalo(ParticleSet<D>& p) {
    imbalance_ = loadImbalance(comm_, static_cast<double>(p.n_moving));
    exchange_.buildHalo(p, partition_.boxes(), radius_);
    // The owned particles' positions: moving ones, then fixed ones (a moving buffer's).
    reference_.assign(p.position.begin(), p.position.begin() + static_cast<std::ptrdiff_t>(D * p.ownedMoving()));
    reference_.insert(reference_.end(), p.position.begin() + static_cast<std::ptrdiff_t>(D * p.n_moving),
                      p.position.begin() + static_cast<std::ptrdiff_t>(D * p.ownedEnd()));
  }

  // Moving particles first, fixed ones after, each group by id.
  static void sortById(ParticleSet<D>& p) {
    std::vector<std::size_t> order(p.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    auto by_id = [&](std::size_t a, std::size_t b) { return p.id[a] < p.id[b]; };
    std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(p.n_moving), by_id);
    std::sort(order.begin() + static_cast<std::ptrdiff_t>(p.n_moving), order.end(), by_id);
    ParticleExchange<D>::reorder(p, order);
  }

  Communicator comm_;
  MPI_Comm handle_ = comm_.handle();
  Domain<D> domain_;
  SpacePartition<D> partition_;
  ParticleExchange<D> exchange_, dealer_;
  double radius_, skin_, tolerance_;
  std::vector<HaloArray> arrays_;
  std::vector<double> reference_;
  double imbalance_ = 1.0;
  std::uint64_t redistributions_ = 0, repartitions_ = 0;
};

}  // namespace

template <int D>
std::unique_ptr<ParticleDistribution<D>> makeMpiDistribution(const Domain<D>& domain, double cutoff, double skin,
                                                             double imbalance_tolerance, int halo_supports) {
  return std::make_unique<MpiDistribution<D>>(domain, cutoff, skin, imbalance_tolerance, halo_supports);
}

template std::unique_ptr<ParticleDistribution<2>> makeMpiDistribution<2>(const Domain<2>&, double, double, double, int);
template std::unique_ptr<ParticleDistribution<3>> makeMpiDistribution<3>(const Domain<3>&, double, double, double, int);

}  // namespace vesph
