#include "vesph/io/output.hpp"

#include <hdf5.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <span>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "vesph/core/types.hpp"
#include "hdf5_support.hpp"

#if VESPH_HAVE_MPI_RUNS
#include <mpi.h>
#ifndef H5_HAVE_PARALLEL
#error "distributed runs (VESPH_HAVE_MPI_RUNS) write their file with parallel HDF5 (CMakeLists.txt finds it)"
#endif
#endif

namespace vesph {
using namespace hdf5io;

namespace {
// A file access list whose close also closes every object still open in the file, so that an
// error between an open and its close cannot leave the file open behind vesph's back.
hid_t strongCloseAccess() {
  const hid_t fapl = checkId(H5Pcreate(H5P_FILE_ACCESS), "file access list");
  H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  return fapl;
}

// Rows [offset, offset + count) of a dataset.
struct RowPiece {
  hsize_t offset, count;
};

#if VESPH_HAVE_MPI_RUNS
// Writes this process's pieces of rows (cols values each; 0: a dataset of rank 1) of the open
// dataset d from `data` (their values one piece after the other), in one collective transfer
// that every process of the file makes (with no piece, it writes nothing).
void writePieces(hid_t d, hid_t mem_type, const void* data, std::size_t cols, std::span<const RowPiece> pieces,
                 const char* name) {
  Handle fspace(checkId(H5Dget_space(d), name), H5Sclose);
  check(H5Sselect_none(fspace), name);
  const int rank = H5Sget_simple_extent_ndims(fspace);
  hsize_t values = 0;
  for (const RowPiece& r : pieces) {
    if (r.count == 0) continue;
    const hsize_t start[2] = {r.offset, 0}, count[2] = {r.count, cols};
    check(H5Sselect_hyperslab(fspace, H5S_SELECT_OR, start, nullptr, count, nullptr), name);
    values += r.count * (rank == 2 ? cols : 1);
  }
  const hsize_t mem_dims[1] = {std::max<hsize_t>(values, 1)};
  Handle mspace(checkId(H5Screate_simple(1, mem_dims, nullptr), name), H5Sclose);
  if (values == 0) check(H5Sselect_none(mspace), name);
  Handle xfer(checkId(H5Pcreate(H5P_DATASET_XFER), name), H5Pclose);
  check(H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE), name);
  check(H5Dwrite(d, mem_type, mspace, fspace, xfer, data), name);
}

// A frame's dataset of `rows` rows written by every process, each its pieces.
void datasetPieces(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t rows,
                   std::size_t cols, std::initializer_list<RowPiece> pieces) {
  hsize_t dims[2] = {rows, cols};
  Handle space(checkId(H5Screate_simple(cols ? 2 : 1, dims, nullptr), name), H5Sclose);
  Handle d(checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Dclose);
  writePieces(d, mem_type, data, cols, std::span<const RowPiece>(pieces.begin(), pieces.size()), name);
}

// writeResizable of a dataset that every process writes its pieces of.
void writeResizablePieces(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data,
                          std::size_t rows, const std::vector<RowPiece>& pieces) {
  // Without a chunk cache: with one, HDF5 1.10 wrote a chunk that a change of extent had
  // pruned back over the values written after it (a changing particle set's checkpoint held
  // the earlier one's values).
  Handle uncached(checkId(H5Pcreate(H5P_DATASET_ACCESS), name), H5Pclose);
  check(H5Pset_chunk_cache(uncached, 0, 0, 1.0), name);
  Handle d(H5Lexists(group, name, H5P_DEFAULT) > 0 ? checkId(H5Dopen2(group, name, uncached), name)
                                                    : createExtensible(group, name, file_type, 1 << 16),
           H5Dclose);
  hsize_t size[1] = {rows};
  check(H5Dset_extent(d, size), name);
  writePieces(d, mem_type, data, 0, pieces, name);
}
#endif
}  // namespace

template <int D>
void OutputWriter<D>::openAccess(std::int64_t fapl) const {
  if (!communicator_) return;
#if VESPH_HAVE_MPI_RUNS
  check(H5Pset_fapl_mpio(fapl, *static_cast<const MPI_Comm*>(communicator_), MPI_INFO_NULL), "parallel file access");
#else
  throw std::logic_error("OutputWriter: a file written by several processes needs a build with VESPH_MPI");
#endif
}

template <int D>
void OutputWriter<D>::writeSharedRows(std::int64_t d, std::int64_t mspace, std::int64_t fspace, const void* data,
                                      const char* what, std::int64_t mem_type) const {
  if (mem_type < 0) mem_type = H5T_NATIVE_DOUBLE;
  if (!communicator_) {
    check(H5Dwrite(d, mem_type, mspace, fspace, H5P_DEFAULT, data), what);
    return;
  }
#if VESPH_HAVE_MPI_RUNS
  if (!writesSharedRows()) {
    check(H5Sselect_none(fspace), what);
    check(H5Sselect_none(mspace), what);
  }
  Handle xfer(checkId(H5Pcreate(H5P_DATASET_XFER), what), H5Pclose);
  check(H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE), what);
  check(H5Dwrite(d, mem_type, mspace, fspace, xfer, data), what);
#endif
}

template <int D>
void OutputWriter<D>::remakeForProcesses() {
  auto remake = [&](hid_t group, const std::string& name) {
    std::size_t rows = 0;
    hsize_t chunk[1] = {0};
    hid_t file_type_id = -1, mem_type_id = -1;
    std::vector<unsigned char> values;
    {
      Handle d(checkId(H5Dopen2(group, name.c_str(), H5P_DEFAULT), name.c_str()), H5Dclose);
      Handle dcpl(checkId(H5Dget_create_plist(d), name.c_str()), H5Pclose);
      H5D_alloc_time_t alloc = H5D_ALLOC_TIME_DEFAULT;
      check(H5Pget_alloc_time(dcpl, &alloc), name.c_str());
      if (H5Pget_layout(dcpl) != H5D_CHUNKED || alloc == H5D_ALLOC_TIME_EARLY) return;
      if (H5Pget_chunk(dcpl, 1, chunk) != 1) return;  // not one of vesph's extensible columns
      rows = datasetRows(group, name.c_str());
      Handle ft(checkId(H5Dget_type(d), name.c_str()), H5Tclose);
      Handle mt(checkId(H5Tget_native_type(ft, H5T_DIR_ASCEND), name.c_str()), H5Tclose);
      values.resize(std::max<std::size_t>(rows, 1) * H5Tget_size(mt));
      if (rows) check(H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), name.c_str());
      file_type_id = H5Tcopy(ft);
      mem_type_id = H5Tcopy(mt);
    }
    Handle file_type(file_type_id, H5Tclose), mem_type(mem_type_id, H5Tclose);
    check(H5Ldelete(group, name.c_str(), H5P_DEFAULT), name.c_str());
    Handle d(createExtensible(group, name.c_str(), file_type, chunk[0]), H5Dclose);
    const hsize_t size[1] = {rows};
    check(H5Dset_extent(d, size), name.c_str());
    if (!rows) return;
    Handle fspace(checkId(H5Dget_space(d), name.c_str()), H5Sclose);
    Handle mspace(checkId(H5Screate_simple(1, size, nullptr), name.c_str()), H5Sclose);
    writeSharedRows(d, mspace, fspace, values.data(), name.c_str(), mem_type);
  };
  auto remakeGroup = [&](const char* path) {
    if (H5Lexists(file_, path, H5P_DEFAULT) <= 0) return;
    Handle g(checkId(H5Gopen2(file_, path, H5P_DEFAULT), path), H5Gclose);
    H5G_info_t info;
    check(H5Gget_info(g, &info), path);
    std::vector<std::string> names;
    for (hsize_t k = 0; k < info.nlinks; ++k) {
      char name[256];
      const ssize_t len = H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
      if (len > 0 && static_cast<std::size_t>(len) < sizeof name) names.emplace_back(name);
    }
    for (const std::string& name : names) {
      H5O_info_t object;
      if (H5Oget_info_by_name(g, name.c_str(), &object, H5P_DEFAULT) < 0) continue;
      if (object.type == H5O_TYPE_DATASET) remake(g, name);
    }
  };
  remakeGroup("diagnostics");
  remakeGroup("checkpoint");
  remakeGroup("checkpoint/arrays");
  for (const GaugeSeries& gauge : gauges_) remakeGroup(("gauges/" + gauge.name).c_str());
}

template <int D>
bool OutputWriter<D>::agreed(bool ok) const {
#if VESPH_HAVE_MPI_RUNS
  if (communicator_) {
    int mine = ok ? 1 : 0, all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_LAND, *static_cast<const MPI_Comm*>(communicator_));
    return all != 0;
  }
#endif
  return ok;
}

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs,
                              double resume_time, const void* communicator)
    : communicator_(communicator), dir_(dir), name_(name), extra_columns_(attrs.extra_columns), gauges_(attrs.gauges) {
#if VESPH_HAVE_MPI_RUNS
  if (communicator_) MPI_Comm_rank(*static_cast<const MPI_Comm*>(communicator_), &rank_);
#endif
  h5_path_ = (std::filesystem::path(dir) / (name + ".h5")).string();
  xdmf_path_ = (std::filesystem::path(dir) / (name + ".xdmf")).string();
  startHdf5();
  {
    Handle fapl(strongCloseAccess(), H5Pclose);
    openAccess(fapl);
    file_ = H5Fopen(h5_path_.c_str(), H5F_ACC_RDWR, fapl);
  }
  if (!agreed(file_ >= 0)) {
    close();
    throw std::runtime_error("cannot open " + h5_path_ + " for writing");
  }
  try {
    if (communicator_) remakeForProcesses();
    reopen(attrs, resume_time);
  } catch (const InputError& e) {
    close();
    throw InputError("--resume: " + h5_path_ + ": " + e.what());
  } catch (...) {
    close();
    throw;
  }
}

template <int D>
void OutputWriter<D>::reopen(const FileAttributes& attrs, double resume_time) {
  replaceAttrString(file_, "scene", attrs.scene_toml);
  // Frames up to the checkpoint stay; later ones (none when the checkpoint is the last frame,
  // as vesph writes it) are removed. A frame's time may differ from resume_time by rounding.
  const double tol = 1e-12 * std::max(1.0, std::abs(resume_time));
  {
    Handle frames(checkId(H5Gopen2(file_, "frames", H5P_DEFAULT), "frames"), H5Gclose);
    for (std::size_t k = 0;; ++k) {
      char gname[32];
      std::snprintf(gname, sizeof gname, "%06zu", k);
      if (H5Lexists(frames, gname, H5P_DEFAULT) <= 0) break;
      Handle g(H5Gopen2(frames, gname, H5P_DEFAULT), H5Gclose);
      if (g < 0) malformed(frames, gname, "not a group");
      char next[32];
      std::snprintf(next, sizeof next, "%06zu", k + 1);
      if (H5Aexists(g, "time") <= 0 && H5Lexists(frames, next, H5P_DEFAULT) <= 0) {
        // The last frame, begun but not finished when a write failed (a full disk): not part
        // of the run before the checkpoint, which is written after its frame.
        check(H5Ldelete(frames, gname, H5P_DEFAULT), "remove an incomplete frame");
        break;
      }
      const double t = readAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE);
      FrameInfo info{gname, t, datasetRows(g, "id"), H5Lexists(g, "extra_stress", H5P_DEFAULT) > 0,
                     H5Lexists(g, "free_surface", H5P_DEFAULT) > 0, H5Lexists(g, "pressure", H5P_DEFAULT) > 0,
                     H5Lexists(g, "extra_stress_zz", H5P_DEFAULT) > 0};
      if (t > resume_time + tol) check(H5Ldelete(frames, gname, H5P_DEFAULT), "remove a frame after the checkpoint");
      else frames_.push_back(info);
    }
  }
  // Diagnostics rows after the checkpoint's time are dropped from every column.
  Handle diag(checkId(H5Gopen2(file_, "diagnostics", H5P_DEFAULT), "diagnostics"), H5Gclose);
  const std::vector<double> times = readVector<double>(diag, "time", H5T_NATIVE_DOUBLE);
  diag_rows_ = 0;
  while (diag_rows_ < times.size() && times[diag_rows_] <= resume_time + tol) ++diag_rows_;
  std::vector<std::string> columns(std::begin(kDiagColumns), std::end(kDiagColumns));
  for (const std::string& c : extra_columns_) columns.push_back(c);
  for (const std::string& col : columns) {
    if (H5Lexists(diag, col.c_str(), H5P_DEFAULT) <= 0) {
      // A hook column the earlier segments did not have: only `escaped`, when
      // checks.leave_domain became "remove" on resume; nothing escaped before, so its rows are 0.
      const std::vector<double> zeros(diag_rows_, 0.0);
      writeResizable(diag, col.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, zeros.data(), zeros.size(), 4096,
                     !communicator_);
      if (communicator_ && diag_rows_ > 0) {
        Handle d(checkId(H5Dopen2(diag, col.c_str(), H5P_DEFAULT), col.c_str()), H5Dclose);
        Handle fspace(checkId(H5Dget_space(d), col.c_str()), H5Sclose);
        const hsize_t count[1] = {diag_rows_};
        Handle mspace(checkId(H5Screate_simple(1, count, nullptr), col.c_str()), H5Sclose);
        writeSharedRows(d, mspace, fspace, zeros.data(), col.c_str());
      }
      continue;
    }
    datasetRows(diag, col.c_str());  // rank 1, or malformed
    Handle d(checkId(H5Dopen2(diag, col.c_str(), H5P_DEFAULT), col.c_str()), H5Dclose);
    hsize_t size[1] = {diag_rows_};
    check(H5Dset_extent(d, size), "truncate diagnostics");
  }
  truncateGauges(resume_time);
  flush("the truncated diagnostics");
  writeXdmf();
}

template <int D>
void OutputWriter<D>::writeCheckpoint(const Checkpoint& c, const CheckpointRows* part) {
  if ((part != nullptr) != (communicator_ != nullptr))
    throw std::logic_error("OutputWriter::writeCheckpoint: a file written together takes each process's rows, a serial one none");
  // A file written together: the state and every carried array are laid out as the state
  // segments, each process's rows of each segment one piece; the ids as the frame's rows.
  std::vector<RowPiece> state_pieces, id_pieces;
  std::size_t state_values = c.state.size(), id_rows = c.id.size();
  std::uint64_t checksum = 0;
  if (part) {
    const FrameRows& r = part->rows;
    std::size_t width = 0;
    for (std::size_t w : part->segment_widths) width += w;
    const std::size_t n_moving = width ? c.state.size() / width : 0;
    if (width == 0 || n_moving * width != c.state.size() || c.id.size() < n_moving)
      throw std::logic_error("OutputWriter::writeCheckpoint: the state is not that of the process's moving particles");
    std::size_t before = 0;
    for (std::size_t w : part->segment_widths) {
      state_pieces.push_back({r.moving_total * before + r.moving_offset * w, n_moving * w});
      before += w;
    }
    id_pieces = {{r.moving_offset, n_moving}, {r.moving_total + r.fixed_offset, c.id.size() - n_moving}};
    state_values = r.moving_total * width;
    id_rows = r.moving_total + r.fixed_total;
    for (const auto& [aname, values] : c.arrays) {
      const long layout = part->layoutOf(aname);
      const std::size_t expected = layout == 0 ? c.state.size() : layout > 0 ? c.id.size() * static_cast<std::size_t>(layout) : values.size();
      if (values.size() != expected)
        throw std::logic_error("OutputWriter::writeCheckpoint: the carried array " + aname + " does not have its layout's size");
    }
    checksum = checkpointChecksum(c, *part, communicator_);
  } else {
    checksum = checkpointChecksum(c);
  }
  // One of the state's datasets: this process's pieces, or the whole.
  auto put = [&](hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t n,
                 std::size_t rows, const std::vector<RowPiece>& pieces) {
    if (!part) return writeResizable(group, name, file_type, mem_type, data, n);
#if VESPH_HAVE_MPI_RUNS
    writeResizablePieces(group, name, file_type, mem_type, data, rows, pieces);
#endif
  };
  bool written = true;
  try {
    Handle g(H5Lexists(file_, "checkpoint", H5P_DEFAULT) > 0
                 ? checkId(H5Gopen2(file_, "checkpoint", H5P_DEFAULT), "checkpoint")
                 : checkId(H5Gcreate2(file_, "checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint"),
             H5Gclose);
    // The time is written last: a checkpoint torn by a failed write (a full disk) has none and
    // is refused on resume, instead of pairing the new state with the old time.
    if (H5Aexists(g, "time") > 0) check(H5Adelete(g, "time"), "time");
    put(g, "state", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.state.data(), c.state.size(), state_values, state_pieces);
    put(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, c.id.data(), c.id.size(), id_rows, id_pieces);
    if (!c.arrays.empty()) {
      Handle arr(H5Lexists(g, "arrays", H5P_DEFAULT) > 0
                     ? checkId(H5Gopen2(g, "arrays", H5P_DEFAULT), "checkpoint arrays")
                     : checkId(H5Gcreate2(g, "arrays", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint arrays"),
                 H5Gclose);
      for (const auto& [aname, values] : c.arrays) {
        if (!part) {
          put(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), 0, {});
          continue;
        }
        // The array's pieces by its layout (CheckpointRows::layoutOf).
        const long layout = part->layoutOf(aname);
        if (layout == 0) {
          put(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), state_values,
              state_pieces);
        } else if (layout > 0) {
          const auto cols = static_cast<std::size_t>(layout);
          std::vector<RowPiece> pieces;
          for (const RowPiece& p : id_pieces) pieces.push_back({p.offset * cols, p.count * cols});
          put(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), id_rows * cols, pieces);
        } else {
          const std::vector<RowPiece> pieces =
              writesSharedRows() ? std::vector<RowPiece>{{0, values.size()}} : std::vector<RowPiece>{};
          put(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), values.size(), pieces);
        }
      }
    }
    // Arrays of an earlier checkpoint that this one does not carry (the integrator's rate after
    // a divergence) are removed: they are not part of this restart point, nor of its checksum.
    if (H5Lexists(g, "arrays", H5P_DEFAULT) > 0) {
      Handle arr(checkId(H5Gopen2(g, "arrays", H5P_DEFAULT), "checkpoint arrays"), H5Gclose);
      H5G_info_t info;
      check(H5Gget_info(arr, &info), "checkpoint arrays");
      std::vector<std::string> stale;
      for (hsize_t k = 0; k < info.nlinks; ++k) {
        char aname[256];
        const ssize_t len = H5Lget_name_by_idx(arr, ".", H5_INDEX_NAME, H5_ITER_INC, k, aname, sizeof aname, H5P_DEFAULT);
        if (len < 0 || static_cast<std::size_t>(len) >= sizeof aname) continue;
        if (!c.find(aname)) stale.emplace_back(aname);
      }
      for (const std::string& aname : stale) check(H5Ldelete(arr, aname.c_str(), H5P_DEFAULT), "stale checkpoint array");
    }
    replaceAttrScalar<std::uint64_t>(g, "checksum", H5T_NATIVE_UINT64, checksum);
    replaceAttrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, c.step);
    replaceAttrScalar<std::uint64_t>(g, "rhs_evals", H5T_NATIVE_UINT64, c.rhs_evals);
    replaceAttrScalar<std::uint64_t>(g, "rejected_steps", H5T_NATIVE_UINT64, c.rejected_steps);
    replaceAttrScalar<std::uint64_t>(g, "neighbour_builds", H5T_NATIVE_UINT64, c.neighbour_builds);
    replaceAttrScalar<double>(g, "wall_seconds", H5T_NATIVE_DOUBLE, c.wall_seconds);
    replaceAttrScalar<double>(g, "max_density_deviation", H5T_NATIVE_DOUBLE, c.max_density_deviation);
    replaceAttrScalar<std::uint64_t>(g, "resumes", H5T_NATIVE_UINT64, c.resumes);
    replaceAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, c.time);
  } catch (const std::runtime_error&) {
    written = false;
  }
  if (!agreed(written)) failed("the checkpoint");
  flush("the checkpoint");
}

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs,
                              const void* communicator)
    : communicator_(communicator), dir_(dir), name_(name), extra_columns_(attrs.extra_columns), gauges_(attrs.gauges) {
  if (extra_columns_.size() > kMaxExtraDiagnostics) throw std::logic_error("too many extra diagnostics columns");
#if VESPH_HAVE_MPI_RUNS
  if (communicator_) MPI_Comm_rank(*static_cast<const MPI_Comm*>(communicator_), &rank_);
#endif
  std::filesystem::create_directories(dir);
  h5_path_ = (std::filesystem::path(dir) / (name + ".h5")).string();
  xdmf_path_ = (std::filesystem::path(dir) / (name + ".xdmf")).string();
  startHdf5();
  {
    Handle fapl(strongCloseAccess(), H5Pclose);
    // An attribute of HDF5's original file format lives in its object's header (64 KiB in
    // all): a resolved scene of thousands of output times did not fit ("HDF5 error: scene").
    // Files for a scene beyond kCompactSceneBytes use the format of HDF5 1.8, whose object
    // headers move large attributes to dense storage; readers (h5py, tools/vesph/output.py)
    // read the attribute as before. Smaller scenes keep the original format, byte for byte.
    if (attrs.scene_toml.size() > kCompactSceneBytes)
      check(H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_LATEST), "file format");
    openAccess(fapl);
    file_ = H5Fcreate(h5_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  }
  if (!agreed(file_ >= 0)) {
    close();
    throw std::runtime_error("cannot create " + h5_path_ + noSpaceNote());
  }
  try {
    attrString(file_, "format", "vesph-1");
    attrScalar<int>(file_, "dim", H5T_NATIVE_INT, attrs.dim);
    attrString(file_, "scene", attrs.scene_toml);
    attrScalar<double>(file_, "dx", H5T_NATIVE_DOUBLE, attrs.dx);
    attrScalar<double>(file_, "h", H5T_NATIVE_DOUBLE, attrs.h);
    attrString(file_, "kernel", attrs.kernel);
    H5Gclose(checkId(H5Gcreate2(file_, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frames"));
    Handle diag(checkId(H5Gcreate2(file_, "diagnostics", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "diagnostics"),
                H5Gclose);
    std::vector<const char*> columns(std::begin(kDiagColumns), std::end(kDiagColumns));
    for (const std::string& c : extra_columns_) columns.push_back(c.c_str());
    for (const char* col : columns) H5Dclose(createExtensible(diag, col, H5T_IEEE_F64LE, 4096));
    createGauges();
  } catch (...) {
    close();
    throw;
  }
  flush("the file's header");
}

template <int D>
OutputWriter<D>::~OutputWriter() {
  close();
}

template <int D>
void OutputWriter<D>::close() {
  if (file_ < 0) return;
  // A close that fails (its last flush, on a full disk) leaves nothing open either: the file's
  // objects are closed with it (H5F_CLOSE_STRONG); HDF5 has nothing left to close at exit.
  H5Fclose(file_);
  file_ = -1;
}

template <int D>
std::string OutputWriter<D>::noSpaceNote() const {
  std::error_code ec;
  const auto space = std::filesystem::space(dir_, ec);
  if (ec || space.available > (std::uintmax_t{1} << 20)) return "";
  return " (" + std::to_string(space.available) + " bytes left on the disk of " + dir_ + ")";
}

template <int D>
void OutputWriter<D>::failed(const std::string& what) {
  const double t = frames_.empty() ? -1.0 : frames_.back().time;
  std::ostringstream os;
  os << "cannot write " << what << " to " << h5_path_ << noSpaceNote();
  close();
  if (t >= 0) os << "; the frames up to t = " << t << " s and their checkpoint are intact: free space, then go on with --resume";
  throw OutputFailure(os.str());
}

template <int D>
void OutputWriter<D>::flush(const char* what) {
  if (H5Fflush(file_, H5F_SCOPE_GLOBAL) < 0) failed(what);
}

template <int D>
void OutputWriter<D>::ensureSpace(std::size_t bytes, const char* what) {
  // Checked before anything of the frame is written: HDF5 does not undo a write that fails half
  // way (a full disk), so the last complete frame and checkpoint stay intact only when the next
  // ones are not begun without room for them. 256 KiB cover HDF5's metadata.
  std::error_code ec;
  const auto space = std::filesystem::space(dir_, ec);
  const std::uintmax_t need = bytes + (std::uintmax_t{1} << 18);
  // A file written together: every process checks its own share, and all stop if one lacks room.
  if (agreed(ec || space.available >= need)) return;
  std::ostringstream os;
  os << "no space left for " << what << " on the disk of " << dir_ << ": " << space.available << " bytes free, about "
     << need << " needed";
  if (!frames_.empty())
    os << "; the frames up to t = " << frames_.back().time
       << " s and their checkpoint are intact: free space, then go on with --resume";
  close();
  throw OutputFailure(os.str());
}

template <int D>
void OutputWriter<D>::appendDiagnostics(const std::vector<DiagnosticsRow>& rows) {
  if (rows.empty()) return;
  Handle diag(checkId(H5Gopen2(file_, "diagnostics", H5P_DEFAULT), "diagnostics"), H5Gclose);
  std::vector<double> col(rows.size());
  const std::size_t base = std::size(kDiagColumns);
  for (std::size_t c = 0; c < base + extra_columns_.size(); ++c) {
    for (std::size_t r = 0; r < rows.size(); ++r) col[r] = c < base ? (&rows[r].time)[c] : rows[r].extra[c - base];
    const char* cname = c < base ? kDiagColumns[c] : extra_columns_[c - base].c_str();
    Handle d(checkId(H5Dopen2(diag, cname, H5P_DEFAULT), cname), H5Dclose);
    hsize_t newsize[1] = {diag_rows_ + rows.size()};
    check(H5Dset_extent(d, newsize), "extend diagnostics");
    Handle fspace(checkId(H5Dget_space(d), cname), H5Sclose);
    hsize_t offset[1] = {diag_rows_}, count[1] = {rows.size()};
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, offset, nullptr, count, nullptr);
    Handle mspace(checkId(H5Screate_simple(1, count, nullptr), cname), H5Sclose);
    writeSharedRows(d, mspace, fspace, col.data(), "diagnostics");
  }
  diag_rows_ += rows.size();
}

template <int D>
void OutputWriter<D>::writeFrame(double time, std::int64_t step, const ParticleSet<D>& p,
                                 const std::vector<DiagnosticsRow>& new_rows, const FrameRows* rows) {
  if (file_ < 0) throw std::runtime_error("cannot write to " + h5_path_ + " after an earlier error");
  if ((rows != nullptr) != (communicator_ != nullptr))
    throw std::logic_error("OutputWriter::writeFrame: a file written together takes each process's rows, a serial one none");
  const std::size_t n = p.size();
  // The frame's rows: this process's particles in a file written together, all of them else.
  const std::size_t frame_rows = rows ? static_cast<std::size_t>(rows->moving_total + rows->fixed_total) : n;
  // Writes one dataset of the frame (cols values per particle; 0: one).
  auto put = [&](hid_t g, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t cols) {
    if (!rows) return dataset(g, name, file_type, mem_type, data, n, cols);
#if VESPH_HAVE_MPI_RUNS
    // The process's moving particles, then its fixed ones: one run of rows each (the data
    // holds them in that order), written in one transfer.
    datasetPieces(g, name, file_type, mem_type, data, frame_rows, cols,
                  {RowPiece{rows->moving_offset, p.n_moving}, RowPiece{rows->moving_total + rows->fixed_offset, p.nFixed()}});
#endif
  };
  {
    // The frame's datasets (id, kind, position, velocity, density, mass, pressure, stresses,
    // flags), the diagnostics rows, and the checkpoint written after it (state, ids, arrays).
    std::size_t field_values = 0;
    for (const char* f : {"pressure", "extra_stress", "elastic_stress_zz"})
      if (const Field* fl = p.fields.find(f)) field_values += fl->components;
    const std::size_t frame_bytes = n * (8 + 1 + 16 * D + 16 + 8 * field_values + 1) +
                                    new_rows.size() * 8 * (std::size(kDiagColumns) + extra_columns_.size());
    ensureSpace(frame_bytes + n * 8 * (2 * D + 2 + field_values), "the next frame");
  }
  char name[32];
  std::snprintf(name, sizeof name, "%06zu", frames_.size());
  const std::string group_path = std::string("/frames/") + name;
  FrameInfo info{name, time, frame_rows, false, false, false, false};
  bool written = true;
  try {
    Handle g(checkId(H5Gcreate2(file_, group_path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frame"), H5Gclose);
    attrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, time);
    attrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, step);
    put(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, p.id.data(), 0);
    put(g, "kind", H5T_STD_U8LE, H5T_NATIVE_UINT8, p.kind.data(), 0);
    put(g, "position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.position.data(), D);
    put(g, "velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.velocity.data(), D);
    put(g, "density", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.density.data(), 0);
    put(g, "mass", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.mass.data(), 0);
    if (const Field* f = p.fields.find("pressure"); f && f->range == Field::Range::all) {
      put(g, "pressure", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), 0);
      info.pressure = true;
    }
    if (const Field* f = p.fields.find("extra_stress"); f && f->range == Field::Range::all) {
      put(g, "extra_stress", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), static_cast<std::size_t>(f->components));
      info.stress = true;
    }
    // 2D models with an out-of-plane stress (XPP, constitutive.hpp): T_zz = S_zz in planar flow
    // (D_zz = 0, so the solvent adds nothing).
    if (const Field* f = p.fields.find("elastic_stress_zz"); D == 2 && f && f->range == Field::Range::all) {
      put(g, "extra_stress_zz", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), 0);
      info.stress_zz = true;
    }
    if (const Field* f = p.fields.find("free_surface"); f && f->range == Field::Range::all) {
      std::vector<std::uint8_t> flag(n);
      for (std::size_t i = 0; i < n; ++i) flag[i] = f->data[i] != 0.0;
      put(g, "free_surface", H5T_STD_U8LE, H5T_NATIVE_UINT8, flag.data(), 0);
      info.free_surface = true;
    }
  } catch (const std::runtime_error&) {
    written = false;
  }
  if (!agreed(written)) failed("a frame");
  try {
    appendDiagnostics(new_rows);
  } catch (const std::runtime_error&) {
    written = false;
  }
  if (!agreed(written)) failed("the diagnostics");
  flush("a frame");
  frames_.push_back(info);
  writeXdmf();
}

template <int D>
void OutputWriter<D>::writeXdmf() const {
  const std::string h5 = std::filesystem::path(h5_path_).filename().string();
  std::ostringstream x;
  x.precision(17);
  x << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto item = [&](const std::string& ds, std::size_t n, int cols, const char* type, int prec) {
    x << "     <DataItem Dimensions=\"" << n;
    if (cols) x << ' ' << cols;
    x << "\" NumberType=\"" << type << "\" Precision=\"" << prec << "\" Format=\"HDF\">" << h5
      << ":" << ds << "</DataItem>\n";
  };
  for (const FrameInfo& f : frames_) {
    const std::string base = "/frames/" + f.group + "/";
    x << "   <Grid Name=\"frame_" << f.group << "\" GridType=\"Uniform\">\n"
      << "    <Time Value=\"" << f.time << "\"/>\n"
      << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << f.n
      << "\" NodesPerElement=\"1\"/>\n"
      << "    <Geometry GeometryType=\"" << (D == 2 ? "XY" : "XYZ") << "\">\n";
    item(base + "position", f.n, D, "Float", 8);
    x << "    </Geometry>\n";
    auto attribute = [&](const char* name, const char* kind, int cols, const char* type, int prec) {
      x << "    <Attribute Name=\"" << name << "\" AttributeType=\"" << kind << "\" Center=\"Node\">\n";
      item(base + name, f.n, cols, type, prec);
      x << "    </Attribute>\n";
    };
    attribute("velocity", "Vector", D, "Float", 8);
    attribute("density", "Scalar", 0, "Float", 8);
    attribute("mass", "Scalar", 0, "Float", 8);
    // uint64 ids declared as Int/8: ParaView 5.11 reads UInt/8 as 32-bit and mangles ids >= 2^32.
    attribute("id", "Scalar", 0, "Int", 8);
    attribute("kind", "Scalar", 0, "UChar", 1);
    if (f.pressure) attribute("pressure", "Scalar", 0, "Float", 8);
    // 3D: "Tensor6", whose component order in XDMF (and in ParaView's XDMF reader, which expands
    // it to a 3x3 tensor) is xx, xy, xz, yy, yz, zz, the order of the dataset, so the file is
    // read as it is stored. 2D keeps "Matrix" (xx, xy, yy): XDMF has no 2D symmetric tensor.
    if (f.stress) attribute("extra_stress", D == 2 ? "Matrix" : "Tensor6", D == 2 ? 3 : 6, "Float", 8);
    if (f.stress_zz) attribute("extra_stress_zz", "Scalar", 0, "Float", 8);
    if (f.free_surface) attribute("free_surface", "Scalar", 0, "UChar", 1);
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  if (writesSharedRows()) writeAtomically(xdmf_path_, x.str());  // one writer of the small text file
}

void writeSummary(const std::string& dir, const nlohmann::json& summary) {
  std::filesystem::create_directories(dir);
  writeAtomically((std::filesystem::path(dir) / "summary.json").string(), summary.dump(2) + "\n");
}

template class OutputWriter<2>;
template class OutputWriter<3>;

}  // namespace vesph
