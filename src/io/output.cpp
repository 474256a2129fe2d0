#include "vesph/io/output.hpp"

#include <hdf5.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <type_traits>

#include "vesph/core/types.hpp"

namespace vesph {
namespace {

// Before vesph's first HDF5 call. After a write failed half way (a full disk, a file size limit),
// HDF5 1.10 cannot close the file (its metadata cannot be flushed) and its own clean-up at exit
// then crashes on that file (SIGSEGV in H5F__close_cb). vesph closes every object it opens
// itself, so that clean-up would only crash: it is switched off before the library starts.
void startHdf5() {
  static const bool started = [] {
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
    return true;
  }();
  (void)started;
}

void check(herr_t status, const char* what) {
  if (status < 0) throw std::runtime_error(std::string("HDF5 error: ") + what);
}
hid_t checkId(hid_t id, const char* what) {
  if (id < 0) throw std::runtime_error(std::string("HDF5 error: ") + what);
  return id;
}

// An HDF5 identifier closed when it goes out of scope, also when an error unwinds the stack: an
// identifier left open keeps the file open after H5Fclose, and HDF5 1.10 then crashes closing
// it at exit when a write had failed (a full disk).
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  operator hid_t() const { return id_; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// The largest scene stored in HDF5's original file format (its attributes share a 64 KiB
// object header with the file's other root attributes).
constexpr std::size_t kCompactSceneBytes = 32768;

void attrString(hid_t loc, const char* name, const std::string& value) {
  Handle type(checkId(H5Tcopy(H5T_C_S1), name), H5Tclose);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  Handle space(checkId(H5Screate(H5S_SCALAR), name), H5Sclose);
  Handle a(checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose);
  check(H5Awrite(a, type, value.empty() ? "" : value.c_str()), name);
}

template <class T>
void attrScalar(hid_t loc, const char* name, hid_t type, T value) {
  Handle space(checkId(H5Screate(H5S_SCALAR), name), H5Sclose);
  Handle a(checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose);
  check(H5Awrite(a, type, &value), name);
}

void dataset(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data,
             std::size_t rows, std::size_t cols) {
  hsize_t dims[2] = {rows, cols};
  Handle space(checkId(H5Screate_simple(cols ? 2 : 1, dims, nullptr), name), H5Sclose);
  Handle d(checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Dclose);
  if (rows) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

constexpr const char* kDiagColumns[] = {"time", "dt", "kinetic_energy", "mass", "max_speed",
                                        "max_density_deviation"};

void writeAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + tmp);
    out << text;
    out.flush();
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

// Attributes that are rewritten (the scene on resume, the checkpoint's counters): delete, then
// create (an attribute's type and size are fixed once created).
void replaceAttrString(hid_t loc, const char* name, const std::string& value) {
  if (H5Aexists(loc, name) > 0) check(H5Adelete(loc, name), name);
  attrString(loc, name, value);
}
template <class T>
void replaceAttrScalar(hid_t loc, const char* name, hid_t type, T value) {
  if (H5Aexists(loc, name) > 0) check(H5Adelete(loc, name), name);
  attrScalar<T>(loc, name, type, value);
}

// Reading a file written by someone else (a resumed run's, possibly damaged): every object is
// checked for the rank, shape and type class it is read as before anything is copied, and a
// mismatch is an InputError naming the object ("/checkpoint/state: ..."); the caller adds the file.
std::string objectPath(hid_t loc, const char* name) {
  char buf[512] = "";
  const ssize_t len = H5Iget_name(loc, buf, sizeof buf);
  std::string path = len > 0 ? std::string(buf) : std::string("?");
  if (path != "/") path += "/";
  return path + name;
}

[[noreturn]] void malformed(hid_t loc, const char* name, const std::string& why) {
  throw InputError(objectPath(loc, name) + ": " + why);
}

// The type class an object of C++ type T is stored as.
template <class T>
H5T_class_t storedClass() {
  return std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER;
}

std::string readAttrString(hid_t loc, const char* name) {
  if (H5Aexists(loc, name) <= 0) return {};
  Handle a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  if (a < 0) malformed(loc, name, "unreadable attribute");
  Handle type(H5Aget_type(a), H5Tclose);
  Handle space(H5Aget_space(a), H5Sclose);
  if (type < 0 || space < 0 || H5Sget_simple_extent_npoints(space) != 1)
    malformed(loc, name, "expected a single string");
  std::string value;
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) <= 0) {
    const std::size_t size = H5Tget_size(type);
    std::vector<char> buf(size + 1, '\0');
    Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem, size + 1);
    if (H5Aread(a, mem, buf.data()) >= 0) value = buf.data();
  }
  return value;
}
template <class T>
T readAttrScalar(hid_t loc, const char* name, hid_t type) {
  if (H5Aexists(loc, name) <= 0) malformed(loc, name, "missing attribute");
  Handle a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
  if (a < 0) malformed(loc, name, "unreadable attribute");
  Handle file_type(H5Aget_type(a), H5Tclose);
  Handle space(H5Aget_space(a), H5Sclose);
  if (file_type < 0 || space < 0 || H5Sget_simple_extent_npoints(space) != 1 ||
      H5Tget_class(file_type) != storedClass<T>())
    malformed(loc, name, std::string("expected a single ") + (storedClass<T>() == H5T_FLOAT ? "floating-point" : "integer") +
                             " value");
  T value{};
  if (H5Aread(a, type, &value) < 0) malformed(loc, name, "unreadable value");
  return value;
}

// The rows of a dataset of rank 1 (cols = 0) or of rank 2 with `cols` columns; anything else is
// malformed.
std::size_t datasetRows(hid_t loc, const char* name, std::size_t cols = 0) {
  if (H5Lexists(loc, name, H5P_DEFAULT) <= 0) malformed(loc, name, "missing dataset");
  Handle d(H5Dopen2(loc, name, H5P_DEFAULT), H5Dclose);
  if (d < 0) malformed(loc, name, "not a dataset");
  Handle space(H5Dget_space(d), H5Sclose);
  const int rank = space < 0 ? -1 : H5Sget_simple_extent_ndims(space);
  if (rank != (cols ? 2 : 1)) malformed(loc, name, "expected a dataset of rank " + std::to_string(cols ? 2 : 1));
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space, dims, nullptr);
  if (cols && dims[1] != cols) malformed(loc, name, "expected " + std::to_string(cols) + " columns");
  return dims[0];
}

template <class T>
std::vector<T> readVector(hid_t loc, const char* name, hid_t mem_type) {
  const std::size_t rows = datasetRows(loc, name);
  Handle d(H5Dopen2(loc, name, H5P_DEFAULT), H5Dclose);
  Handle file_type(H5Dget_type(d), H5Tclose);
  if (file_type < 0 || H5Tget_class(file_type) != storedClass<T>())
    malformed(loc, name, std::string("expected ") + (storedClass<T>() == H5T_FLOAT ? "floating-point" : "integer") + " values");
  std::vector<T> v(rows);
  if (!v.empty() && H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    malformed(loc, name, "unreadable values");
  return v;
}

// An empty 1-D dataset that can grow and shrink (chunked, unlimited): the diagnostics columns
// and the checkpoint's arrays. Returns the open dataset.
hid_t createExtensible(hid_t group, const char* name, hid_t file_type, hsize_t chunk_rows) {
  hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, chunk[1] = {chunk_rows};
  Handle space(checkId(H5Screate_simple(1, dims, maxdims), name), H5Sclose);
  Handle plist(checkId(H5Pcreate(H5P_DATASET_CREATE), name), H5Pclose);
  H5Pset_chunk(plist, 1, chunk);
  return checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, plist, H5P_DEFAULT), name);
}

// Writes a whole 1-D extensible dataset, created on first use and then overwritten in place:
// the checkpoint does not make the file grow with every frame.
void writeResizable(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t n,
                    hsize_t chunk_rows = 1 << 16) {
  Handle d(H5Lexists(group, name, H5P_DEFAULT) > 0 ? checkId(H5Dopen2(group, name, H5P_DEFAULT), name)
                                                    : createExtensible(group, name, file_type, chunk_rows),
           H5Dclose);
  hsize_t size[1] = {n};
  check(H5Dset_extent(d, size), name);
  if (n) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

}  // namespace

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

namespace {
// A file access list whose close also closes every object still open in the file, so that an
// error between an open and its close cannot leave the file open behind vesph's back.
hid_t strongCloseAccess() {
  const hid_t fapl = checkId(H5Pcreate(H5P_FILE_ACCESS), "file access list");
  H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  return fapl;
}
}  // namespace

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs,
                              double resume_time)
    : dir_(dir), name_(name), extra_columns_(attrs.extra_columns) {
  h5_path_ = (std::filesystem::path(dir) / (name + ".h5")).string();
  xdmf_path_ = (std::filesystem::path(dir) / (name + ".xdmf")).string();
  startHdf5();
  {
    Handle fapl(strongCloseAccess(), H5Pclose);
    file_ = H5Fopen(h5_path_.c_str(), H5F_ACC_RDWR, fapl);
  }
  if (file_ < 0) throw std::runtime_error("cannot open " + h5_path_ + " for writing");
  try {
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
      writeResizable(diag, col.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, zeros.data(), zeros.size(), 4096);
      continue;
    }
    datasetRows(diag, col.c_str());  // rank 1, or malformed
    Handle d(checkId(H5Dopen2(diag, col.c_str(), H5P_DEFAULT), col.c_str()), H5Dclose);
    hsize_t size[1] = {diag_rows_};
    check(H5Dset_extent(d, size), "truncate diagnostics");
  }
  flush("the truncated diagnostics");
  writeXdmf();
}

template <int D>
void OutputWriter<D>::writeCheckpoint(const Checkpoint& c) {
  try {
    Handle g(H5Lexists(file_, "checkpoint", H5P_DEFAULT) > 0
                 ? checkId(H5Gopen2(file_, "checkpoint", H5P_DEFAULT), "checkpoint")
                 : checkId(H5Gcreate2(file_, "checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint"),
             H5Gclose);
    // The time is written last: a checkpoint torn by a failed write (a full disk) has none and
    // is refused on resume, instead of pairing the new state with the old time.
    if (H5Aexists(g, "time") > 0) check(H5Adelete(g, "time"), "time");
    writeResizable(g, "state", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.state.data(), c.state.size());
    writeResizable(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, c.id.data(), c.id.size());
    if (!c.arrays.empty()) {
      Handle arr(H5Lexists(g, "arrays", H5P_DEFAULT) > 0
                     ? checkId(H5Gopen2(g, "arrays", H5P_DEFAULT), "checkpoint arrays")
                     : checkId(H5Gcreate2(g, "arrays", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint arrays"),
                 H5Gclose);
      for (const auto& [aname, values] : c.arrays)
        writeResizable(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size());
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
    replaceAttrScalar<std::uint64_t>(g, "checksum", H5T_NATIVE_UINT64, checkpointChecksum(c));
    replaceAttrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, c.step);
    replaceAttrScalar<std::uint64_t>(g, "rhs_evals", H5T_NATIVE_UINT64, c.rhs_evals);
    replaceAttrScalar<std::uint64_t>(g, "rejected_steps", H5T_NATIVE_UINT64, c.rejected_steps);
    replaceAttrScalar<std::uint64_t>(g, "neighbour_builds", H5T_NATIVE_UINT64, c.neighbour_builds);
    replaceAttrScalar<double>(g, "wall_seconds", H5T_NATIVE_DOUBLE, c.wall_seconds);
    replaceAttrScalar<double>(g, "max_density_deviation", H5T_NATIVE_DOUBLE, c.max_density_deviation);
    replaceAttrScalar<std::uint64_t>(g, "resumes", H5T_NATIVE_UINT64, c.resumes);
    replaceAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, c.time);
  } catch (const std::runtime_error&) {
    failed("the checkpoint");
  }
  flush("the checkpoint");
}

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs)
    : dir_(dir), name_(name), extra_columns_(attrs.extra_columns) {
  if (extra_columns_.size() > kMaxExtraDiagnostics) throw std::logic_error("too many extra diagnostics columns");
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
    file_ = H5Fcreate(h5_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  }
  if (file_ < 0) throw std::runtime_error("cannot create " + h5_path_ + noSpaceNote());
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
  throw std::runtime_error(os.str());
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
  if (ec || space.available >= need) return;
  std::ostringstream os;
  os << "no space left for " << what << " on the disk of " << dir_ << ": " << space.available << " bytes free, about "
     << need << " needed";
  if (!frames_.empty())
    os << "; the frames up to t = " << frames_.back().time
       << " s and their checkpoint are intact: free space, then go on with --resume";
  close();
  throw std::runtime_error(os.str());
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
    check(H5Dwrite(d, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, col.data()), "diagnostics");
  }
  diag_rows_ += rows.size();
}

template <int D>
void OutputWriter<D>::writeFrame(double time, std::int64_t step, const ParticleSet<D>& p,
                                 const std::vector<DiagnosticsRow>& new_rows) {
  if (file_ < 0) throw std::runtime_error("cannot write to " + h5_path_ + " after an earlier error");
  const std::size_t n = p.size();
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
  FrameInfo info{name, time, n, false, false, false, false};
  try {
    Handle g(checkId(H5Gcreate2(file_, group_path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frame"), H5Gclose);
    attrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, time);
    attrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, step);
    dataset(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, p.id.data(), n, 0);
    dataset(g, "kind", H5T_STD_U8LE, H5T_NATIVE_UINT8, p.kind.data(), n, 0);
    dataset(g, "position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.position.data(), n, D);
    dataset(g, "velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.velocity.data(), n, D);
    dataset(g, "density", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.density.data(), n, 0);
    dataset(g, "mass", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.mass.data(), n, 0);
    if (const Field* f = p.fields.find("pressure"); f && f->range == Field::Range::all) {
      dataset(g, "pressure", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), n, 0);
      info.pressure = true;
    }
    if (const Field* f = p.fields.find("extra_stress"); f && f->range == Field::Range::all) {
      dataset(g, "extra_stress", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), n, f->components);
      info.stress = true;
    }
    // 2D models with an out-of-plane stress (XPP, constitutive.hpp): T_zz = S_zz in planar flow
    // (D_zz = 0, so the solvent adds nothing).
    if (const Field* f = p.fields.find("elastic_stress_zz"); D == 2 && f && f->range == Field::Range::all) {
      dataset(g, "extra_stress_zz", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, f->data.data(), n, 0);
      info.stress_zz = true;
    }
    if (const Field* f = p.fields.find("free_surface"); f && f->range == Field::Range::all) {
      std::vector<std::uint8_t> flag(n);
      for (std::size_t i = 0; i < n; ++i) flag[i] = f->data[i] != 0.0;
      dataset(g, "free_surface", H5T_STD_U8LE, H5T_NATIVE_UINT8, flag.data(), n, 0);
      info.free_surface = true;
    }
  } catch (const std::runtime_error&) {
    failed("a frame");
  }
  try {
    appendDiagnostics(new_rows);
  } catch (const std::runtime_error&) {
    failed("the diagnostics");
  }
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
    if (f.stress) attribute("extra_stress", "Matrix", D == 2 ? 3 : 6, "Float", 8);
    if (f.stress_zz) attribute("extra_stress_zz", "Scalar", 0, "Float", 8);
    if (f.free_surface) attribute("free_surface", "Scalar", 0, "UChar", 1);
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  writeAtomically(xdmf_path_, x.str());
}

void writeSummary(const std::string& dir, const nlohmann::json& summary) {
  std::filesystem::create_directories(dir);
  writeAtomically((std::filesystem::path(dir) / "summary.json").string(), summary.dump(2) + "\n");
}

template class OutputWriter<2>;
template class OutputWriter<3>;

}  // namespace vesph
