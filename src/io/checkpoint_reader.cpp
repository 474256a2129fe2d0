// Reading a checkpoint back for `vesph run --resume` (docs/architecture.md "Checkpoints"): the
// state, ids, totals and carried arrays of the last frame, every object checked before it is
// read, and the checksum written with them.
#include "vesph/io/output.hpp"

#include <bit>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "hdf5_support.hpp"

#if VESPH_HAVE_MPI_RUNS
#include <mpi.h>
#endif

namespace vesph {
using namespace hdf5io;

namespace {
struct Fnv1a64 {
  std::uint64_t hash = 14695981039346656037ull;  // the FNV-1a offset basis
  void add(const void* data, std::size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < bytes; ++k) hash = (hash ^ b[k]) * 1099511628211ull;  // the FNV prime
  }
  template <class T>
  void addVector(const std::vector<T>& v) {
    const std::uint64_t n = v.size();
    add(&n, sizeof n);
    add(v.data(), v.size() * sizeof(T));
  }
};
}  // namespace

std::uint64_t checkpointChecksum(const Checkpoint& c) {
  static_assert(std::endian::native == std::endian::little, "the checksum hashes the stored (little-endian) bytes");
  Fnv1a64 h;
  h.addVector(c.state);
  h.addVector(c.id);
  std::vector<const std::pair<std::string, std::vector<double>>*> arrays;
  for (const auto& a : c.arrays) arrays.push_back(&a);
  std::sort(arrays.begin(), arrays.end(), [](const auto* a, const auto* b) { return a->first < b->first; });
  for (const auto* a : arrays) {
    h.add(a->first.data(), a->first.size() + 1);  // with its terminating zero
    h.addVector(a->second);
  }
  return h.hash;
}

std::uint64_t checkpointChecksum(const Checkpoint& part, const CheckpointRows& rows, const void* communicator) {
#if VESPH_HAVE_MPI_RUNS
  // FNV-1a is sequential: the hash goes from process to process in rank order through each run
  // of bytes that the processes hold in turn (a state segment, the ids), and every process
  // continues from the last one's (a few messages of 8 bytes per run).
  const MPI_Comm comm = *static_cast<const MPI_Comm*>(communicator);
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  Fnv1a64 h;
  auto inTurn = [&](const void* data, std::size_t bytes) {
    if (rank > 0) MPI_Recv(&h.hash, 1, MPI_UINT64_T, rank - 1, 0, comm, MPI_STATUS_IGNORE);
    h.add(data, bytes);
    if (rank + 1 < size) MPI_Send(&h.hash, 1, MPI_UINT64_T, rank + 1, 0, comm);
    MPI_Bcast(&h.hash, 1, MPI_UINT64_T, size - 1, comm);
  };
  const FrameRows& r = rows.rows;
  std::size_t width = 0;
  for (std::size_t w : rows.segment_widths) width += w;
  const std::size_t n_moving = width ? part.state.size() / width : 0;
  auto stateLaidOut = [&](const std::vector<double>& values) {
    const std::uint64_t n = r.moving_total * width;
    h.add(&n, sizeof n);
    std::size_t off = 0;
    for (std::size_t w : rows.segment_widths) {
      inTurn(values.data() + off, n_moving * w * sizeof(double));
      off += n_moving * w;
    }
  };
  stateLaidOut(part.state);
  const std::uint64_t ids = r.moving_total + r.fixed_total;
  h.add(&ids, sizeof ids);
  inTurn(part.id.data(), n_moving * sizeof(std::uint64_t));
  inTurn(part.id.data() + n_moving, (part.id.size() - n_moving) * sizeof(std::uint64_t));
  std::vector<const std::pair<std::string, std::vector<double>>*> arrays;
  for (const auto& a : part.arrays) arrays.push_back(&a);
  std::sort(arrays.begin(), arrays.end(), [](const auto* a, const auto* b) { return a->first < b->first; });
  for (const auto* a : arrays) {
    h.add(a->first.data(), a->first.size() + 1);
    const long layout = rows.layoutOf(a->first);
    if (layout == 0) {
      stateLaidOut(a->second);
    } else if (layout > 0) {  // the frame's rows: every moving row, then every fixed one
      const auto cols = static_cast<std::size_t>(layout);
      const std::uint64_t n = ids * cols;
      h.add(&n, sizeof n);
      inTurn(a->second.data(), n_moving * cols * sizeof(double));
      inTurn(a->second.data() + n_moving * cols, (part.id.size() - n_moving) * cols * sizeof(double));
    } else {  // the same on every process
      h.addVector(a->second);
    }
  }
  return h.hash;
#else
  (void)part;
  (void)rows;
  (void)communicator;
  throw std::logic_error("checkpointChecksum across processes needs a build with VESPH_MPI");
#endif
}

ResumeSource readResumeSource(const std::string& dir, const std::string& name) {
  const std::string path = (std::filesystem::path(dir) / (name + ".h5")).string();
  if (!std::filesystem::exists(path))
    throw InputError("--resume: nothing to resume: " + path + " does not exist (run without --resume first)");
  startHdf5();
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (file < 0) throw InputError("--resume: " + path + " is not a readable HDF5 file");
  ResumeSource r;
  try {
    if (readAttrString(file, "format") != "vesph-1") throw InputError("--resume: " + path + " is not a vesph-1 output file");
    r.scene_toml = readAttrString(file, "scene");
    if (H5Lexists(file, "checkpoint", H5P_DEFAULT) <= 0)
      throw InputError("--resume: " + path + " holds no checkpoint (written by a vesph without --resume support)");
    Handle g(H5Gopen2(file, "checkpoint", H5P_DEFAULT), H5Gclose);
    if (g < 0) malformed(file, "checkpoint", "not a group");
    Checkpoint& c = r.checkpoint;
    c.time = readAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE);
    c.step = readAttrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64);
    c.rhs_evals = readAttrScalar<std::uint64_t>(g, "rhs_evals", H5T_NATIVE_UINT64);
    c.rejected_steps = readAttrScalar<std::uint64_t>(g, "rejected_steps", H5T_NATIVE_UINT64);
    c.neighbour_builds = readAttrScalar<std::uint64_t>(g, "neighbour_builds", H5T_NATIVE_UINT64);
    c.wall_seconds = readAttrScalar<double>(g, "wall_seconds", H5T_NATIVE_DOUBLE);
    c.max_density_deviation = readAttrScalar<double>(g, "max_density_deviation", H5T_NATIVE_DOUBLE);
    c.resumes = readAttrScalar<std::uint64_t>(g, "resumes", H5T_NATIVE_UINT64);
    c.state = readVector<double>(g, "state", H5T_NATIVE_DOUBLE);
    c.id = readVector<std::uint64_t>(g, "id", H5T_NATIVE_UINT64);
    if (H5Lexists(g, "arrays", H5P_DEFAULT) > 0) {
      Handle arr(H5Gopen2(g, "arrays", H5P_DEFAULT), H5Gclose);
      H5G_info_t info;
      if (arr < 0 || H5Gget_info(arr, &info) < 0) malformed(g, "arrays", "not a group");
      for (hsize_t k = 0; k < info.nlinks; ++k) {
        char aname[256];
        const ssize_t len = H5Lget_name_by_idx(arr, ".", H5_INDEX_NAME, H5_ITER_INC, k, aname, sizeof aname, H5P_DEFAULT);
        if (len < 0) continue;
        if (static_cast<std::size_t>(len) >= sizeof aname) malformed(arr, "", "an array name longer than 255 characters");
        c.arrays.emplace_back(aname, readVector<double>(arr, aname, H5T_NATIVE_DOUBLE));
      }
    }
    if (H5Aexists(g, "checksum") > 0) c.checksum = readAttrScalar<std::uint64_t>(g, "checksum", H5T_NATIVE_UINT64);
    if (H5Lexists(file, "frames", H5P_DEFAULT) > 0) {
      Handle frames(H5Gopen2(file, "frames", H5P_DEFAULT), H5Gclose);
      if (frames < 0) malformed(file, "frames", "not a group");
      for (std::size_t k = 0;; ++k) {
        char gname[32];
        std::snprintf(gname, sizeof gname, "%06zu", k);
        if (H5Lexists(frames, gname, H5P_DEFAULT) <= 0) break;
        Handle fg(H5Gopen2(frames, gname, H5P_DEFAULT), H5Gclose);
        if (fg < 0) malformed(frames, gname, "not a group");
        if (H5Aexists(fg, "time") > 0) r.frame_times.push_back(readAttrScalar<double>(fg, "time", H5T_NATIVE_DOUBLE));
      }
    }
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.rfind("--resume: ", 0) == 0) throw;
    throw InputError("--resume: " + path + ": " + what);
  }
  return r;
}


}  // namespace vesph
