#include "vesph/parallel/communicator.hpp"

#include <cstdlib>
#include <mutex>
#include <stdexcept>

namespace vesph {
namespace {

void finaliseMpi() {
  int finalised = 0;
  MPI_Finalized(&finalised);
  if (!finalised) MPI_Finalize();
}

void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

}  // namespace

void ensureMpiInitialised() {
  static std::once_flag once;
  std::call_once(once, [] {
    int initialised = 0;
    MPI_Initialized(&initialised);
    if (initialised) return;
    // A process not started by mpirun is an MPI singleton, and Open MPI then forks a daemon
    // (orted) that inherits every open descriptor, the output file's among them, with its
    // HDF5 lock: after vesph exits the daemon lingers a moment holding it, and a `--resume`
    // started at once finds the file locked. A singleton needs no daemon: the isolated mode
    // starts none. A value the user set (or mpirun's launch) is kept.
    setenv("OMPI_MCA_ess_singleton_isolated", "1", /*overwrite=*/0);
    int provided = 0;
    if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
      throw std::runtime_error("MPI could not be initialised");
    std::atexit(finaliseMpi);
  });
}

bool launchedWithSeveralProcesses() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* v = std::getenv(name); v != nullptr && std::atoi(v) > 1) return true;
  return false;
}

Communicator Communicator::world() {
  ensureMpiInitialised();
  return Communicator(MPI_COMM_WORLD);
}

Communicator::Communicator(MPI_Comm comm) : comm_(comm) {
  check(MPI_Comm_rank(comm_, &rank_), "MPI_Comm_rank");
  check(MPI_Comm_size(comm_, &size_), "MPI_Comm_size");
}

double Communicator::min(double local) const {
  double out = local;
  check(MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MIN, comm_), "MPI_Allreduce");
  return out;
}

double Communicator::max(double local) const {
  double out = local;
  check(MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MAX, comm_), "MPI_Allreduce");
  return out;
}

double Communicator::sum(double local) const {
  double out = local;
  check(MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_SUM, comm_), "MPI_Allreduce");
  return out;
}

std::uint64_t Communicator::sum(std::uint64_t local) const {
  std::uint64_t out = local;
  check(MPI_Allreduce(&local, &out, 1, MPI_UINT64_T, MPI_SUM, comm_), "MPI_Allreduce");
  return out;
}

double loadImbalance(const Communicator& comm, double local_load) {
  const double total = comm.sum(local_load), largest = comm.max(local_load);
  if (total <= 0.0) return 1.0;
  return largest / (total / comm.size());
}

}  // namespace vesph
