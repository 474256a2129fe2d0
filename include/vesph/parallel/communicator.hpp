#pragma once
// The processes of a distributed run (docs/architecture.md "Distributed runs"): a thin wrapper
// over an MPI communicator with the reductions the run needs. MPI starts on first use
// (ensureMpiInitialised): a serial run that never asks for a communicator never starts it.
#include <mpi.h>

#include <cstdint>

namespace vesph {

// Initialises MPI once per process (MPI_THREAD_FUNNELED: OpenMP threads never call MPI) and
// finalises it at exit. Without mpirun the process is an MPI singleton. Also used by the
// hypre solvers (src/isph/amg_solver.cpp), which need MPI even in a serial run.
void ensureMpiInitialised();

// Whether this process was started by an MPI launcher with more than one process (Open MPI's
// OMPI_COMM_WORLD_SIZE, or the PMI_SIZE of MPICH and Slurm): then a run is distributed. Reads
// the environment only; does not start MPI.
bool launchedWithSeveralProcesses();

class Communicator {
 public:
  // The processes mpirun started (MPI_COMM_WORLD); a lone process is a world of one.
  static Communicator world();
  explicit Communicator(MPI_Comm comm);

  int rank() const { return rank_; }
  int size() const { return size_; }
  MPI_Comm handle() const { return comm_; }

  double min(double local) const;
  double max(double local) const;
  double sum(double local) const;
  std::uint64_t sum(std::uint64_t local) const;

 private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
};

// Load imbalance of a distributed quantity: the largest rank's share over the mean (1 = even).
// Zero load everywhere counts as even.
double loadImbalance(const Communicator& comm, double local_load);

}  // namespace vesph
