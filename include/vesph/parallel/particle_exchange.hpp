#pragma once
// Particles between ranks (docs/architecture.md "Distributed runs"): migration to the rank
// that owns them, and the halo — copies (ghosts) of the particles that other ranks own within a
// radius of this rank's box, so that the neighbour loop of an owned particle finds every
// neighbour it would find in a serial run.
//
// Layout of a rank's particle set with its halo:
//   [owned moving | ghost moving | owned fixed | ghost fixed]
// n_moving counts the ghost moving particles too, so that the neighbour list sorts a ghost of a
// fluid particle among the fluid neighbours; the ODE state and every per-particle result belong
// to the owned ones only (layout()). Ghosts carry every array and field their owners carry, and
// refresh() copies the owners' current values of chosen arrays into them (between passes).
//
// Every exchange is point to point with the neighbour ranks (those whose boxes lie within the
// radius), except migration, which is an all-to-all (its counts are one exchange with every
// rank, at neighbour-list rebuilds only).
#include <cstdint>
#include <span>
#include <vector>

#include "vesph/core/distribution.hpp"  // HaloArray
#include "vesph/core/particles.hpp"
#include "vesph/parallel/communicator.hpp"
#include "vesph/parallel/space_partition.hpp"

namespace vesph {

struct HaloLayout {
  std::size_t owned_moving = 0, ghost_moving = 0, owned_fixed = 0, ghost_fixed = 0;
  std::size_t ghosts() const { return ghost_moving + ghost_fixed; }
};

// What the halo cost (the communication model of docs/performance.md is checked against these).
struct HaloCounters {
  std::size_t neighbour_ranks = 0;
  std::size_t ghosts_received = 0;       // ghost particles this rank holds
  std::size_t ghosts_sent = 0;           // copies of this rank's particles held elsewhere
  std::uint64_t refreshes = 0;
  std::uint64_t messages_sent = 0;       // point-to-point messages of every refresh so far
  std::uint64_t bytes_sent = 0;          // their payload
  std::uint64_t particles_migrated = 0;  // sent to another owner, over every migration
};

template <int D>
class ParticleExchange {
 public:
  ParticleExchange(const Communicator& comm, const Domain<D>& domain);

  // Sends each particle i to rank destination[i], every array and field with it. The set must
  // hold no halo. Afterwards the moving particles come first, then the fixed ones, each in
  // source-rank order (a rank's own kept particles at its own place among the sources), each
  // source's in their previous order. Collective. Returns the particles this rank sent away.
  std::size_t migrate(ParticleSet<D>& p, std::span<const int> destination);

  // Keeps the particles flagged (one flag per particle), in their order: the initial share of a
  // rank that built the whole scene. Local.
  void keepOnly(ParticleSet<D>& p, std::span<const char> keep);

  // Puts the particles in the order given (order[t]: the particle that goes to place t; moving
  // particles must stay in [0, n_moving)), every array and field with them. Local.
  static void reorder(ParticleSet<D>& p, std::span<const std::size_t> order);

  // Appends the halo: a copy of every particle another rank owns within `radius` of this
  // rank's box (boxes: every rank's, from the partition; radius: the neighbour search's cutoff
  // plus its skin, so that the halo holds until the next rebuild). Collective.
  void buildHalo(ParticleSet<D>& p, const std::vector<Box<D>>& boxes, double radius);

  // Removes the halo (before a migration or a rearrangement of the owned particles).
  void removeHalo(ParticleSet<D>& p);

  // Copies the owners' current values of the arrays into their ghosts. Collective among
  // neighbours; allocates only when a refresh carries more than any before it.
  void refresh(std::span<const HaloArray> arrays);

  // Position, velocity and density, then every field of the set, in the store's order.
  static std::vector<HaloArray> everyArray(ParticleSet<D>& p);

  const HaloLayout& layout() const { return layout_; }
  bool hasHalo() const { return has_halo_; }
  const std::vector<int>& neighbourRanks() const { return neighbours_; }
  const HaloCounters& counters() const { return counters_; }

 private:
  Communicator comm_;
  Domain<D> domain_;
  HaloLayout layout_;
  bool has_halo_ = false;
  std::vector<int> neighbours_;
  // Per neighbour: this rank's particles it holds ghosts of (indices into the set with the
  // halo), moving ones first; and where its particles' ghosts lie here.
  std::vector<std::vector<Index>> send_;
  std::vector<std::size_t> send_moving_;
  std::vector<std::size_t> recv_moving_, recv_fixed_, recv_moving_at_, recv_fixed_at_;
  std::size_t n_moving_with_halo_ = 0;
  std::vector<std::vector<double>> send_buffer_, recv_buffer_;
  std::vector<MPI_Request> requests_;
  HaloCounters counters_;
};

}  // namespace vesph
