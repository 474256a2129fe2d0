#pragma once
// What a run across processes asks of its particle distribution (docs/architecture.md
// "Distributed runs"): the SPH system holds one (null in a serial run, which then runs exactly
// as without it) and calls it at fixed points of the right-hand side and between steps; the
// implementation lives in parallel/ (MPI, Zoltan), so nothing above core/ depends on MPI.
//
// The particle set of a process: [owned moving | ghost moving | owned fixed | ghost fixed]
// (ParticleSet::n_ghost_moving, n_ghost_fixed); the ghosts are copies of particles that other
// processes own within the neighbour search radius plus skin of this one's part of the domain.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vesph/core/particles.hpp"

namespace vesph {

// What the distribution cost, summed over the processes (summary.json "distribution"; the
// communication model of docs/performance.md is checked against it).
struct DistributionCounters {
  std::uint64_t ghosts = 0;           // ghost particles held at the last halo build
  std::uint64_t neighbour_links = 0;  // (process, neighbour process) pairs exchanging halos
  std::uint64_t refreshes = 0;        // halo refreshes (per process: every process makes each)
  std::uint64_t messages = 0;         // their point-to-point messages
  std::uint64_t bytes = 0;            // their payload
  std::uint64_t migrated = 0;         // particles that changed owner
};

// A process's part of a frame written by every process into one file (OutputWriter's
// FrameRows): its particles, and where their rows lie among all processes' — the frame holds
// every moving particle first (rows [0, moving_total)), then every fixed one.
template <int D>
struct OutputShare {
  ParticleSet<D> particles;
  std::uint64_t moving_offset = 0, moving_total = 0;  // rows of its moving particles
  std::uint64_t fixed_offset = 0, fixed_total = 0;    // of its fixed ones, counted after the moving
};

// One per-particle array a halo refresh copies to the ghosts: `components` doubles per particle,
// laid out over `range` (all: every particle; moving: [0, n_moving); fixed: [n_moving, size())).
struct HaloArray {
  double* data;
  int components;
  Field::Range range;
};

// What the step just accepted asks of every process (ParticleDistribution::needsRedistribution).
struct RedistributionNeed {
  bool redistribute = false;     // the halo must be built again before the next step
  bool particle_changes = false; // some process's hooks add or remove particles
};

template <int D>
class ParticleDistribution {
 public:
  virtual ~ParticleDistribution() = default;

  virtual int rank() const = 0;
  virtual int size() const = 0;
  // The MPI communicator of the processes (points to an MPI_Comm; OdeSystem::stateCommunicator).
  virtual const void* communicator() const = 0;

  // Once, with the whole scene on every process: keeps this process's share (a partition of
  // the domain by weight) and appends its ghosts. Collective.
  virtual void distribute(ParticleSet<D>& p) = 0;
  // The owners' positions, velocities, densities and the given fields into the ghosts (after the
  // state is unpacked). Collective.
  virtual void refreshState(ParticleSet<D>& p, std::span<Field* const> evolving) = 0;
  // The owners' velocities, densities and every field into the ghosts (after a phase that wrote
  // per-particle values a later phase reads from neighbours). Collective.
  virtual void refreshFields(ParticleSet<D>& p) = 0;
  // The owners' values of the given arrays into the ghosts (a step hook's own per-particle
  // values: the ISPH projection's unknown numbers, pressures, corrected velocities). Collective.
  virtual void refreshArrays(std::span<const HaloArray> arrays) = 0;
  // Whether some owned particle (fluid, or a moving fixed one: an inflow buffer's) moved so far
  // since the halo was built that the halo may miss a neighbour before the next step ends, a
  // step moving a particle by up to step_motion (m), or some process has particle changes of
  // its hooks to make (changes_here: an inflow's releases, an outflow's removals). Collective
  // (every process gets the same answer).
  virtual RedistributionNeed needsRedistribution(const ParticleSet<D>& p, double step_motion, bool changes_here) = 0;
  // Removes the ghosts (before the hooks' particle changes, which a set without ghosts takes).
  virtual void removeHalo(ParticleSet<D>& p) = 0;
  // Removes the ghosts, sends particles to their owners (repartitioning when the load has
  // become uneven), and builds the halo again. Collective.
  virtual void redistribute(ParticleSet<D>& p) = 0;
  // A copy of this process's owned particles (the halo left out), every array and field with
  // them: what a frame and its checkpoint are dealt from (the caller may add fields). Local.
  virtual ParticleSet<D> owned(const ParticleSet<D>& p) = 0;
  // Deals the owned particles of every process out for writing one file together: process r
  // gets those whose ids lie in the r-th of size() equal blocks of the ids, moving ones first,
  // each group sorted by id, and learns where its rows go (OutputShare). Collective.
  virtual OutputShare<D> deal(ParticleSet<D> owned) = 0;

  // Reductions over the processes.
  virtual double sum(double local) = 0;
  virtual double max(double local) = 0;
  virtual std::uint64_t sum(std::uint64_t local) = 0;
  // Element-wise sums and maxima, in place (every process gets them). Collective.
  virtual void sum(std::span<double> values) = 0;
  virtual void max(std::span<double> values) = 0;
  // Every process's values, concatenated in rank order (every process gets them). Collective.
  virtual std::vector<double> allGather(const std::vector<double>& local) = 0;
  // The first non-empty message in rank order (empty when every process's is). Collective.
  virtual std::string firstMessage(const std::string& local) = 0;
  // Ends every process at once (exit code 1) after an error that only this one met, which the
  // others, waiting for it in a collective call, cannot learn of: the message goes to stderr.
  [[noreturn]] virtual void abort(const std::string& message) = 0;

  // The largest process's share of the moving particles over the mean (1: even), at the last
  // (re)distribution; the (re)distributions and the ghosts held, for the summary.
  virtual double imbalance() const = 0;
  virtual std::uint64_t redistributions() const = 0;
  virtual std::uint64_t repartitions() const = 0;
  // Collective.
  virtual DistributionCounters counters() = 0;
};

}  // namespace vesph
