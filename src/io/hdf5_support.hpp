#pragma once
// HDF5 support shared by the output writer (output.cpp) and the checkpoint reader
// (checkpoint_reader.cpp): errors as exceptions, identifiers closed by scope, attributes and
// datasets written and read with their rank, shape and type checked. Private to src/io.
#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "vesph/core/types.hpp"

namespace vesph::hdf5io {


// Before vesph's first HDF5 call. After a write failed half way (a full disk, a file size limit),
// HDF5 1.10 cannot close the file (its metadata cannot be flushed) and its own clean-up at exit
// then crashes on that file (SIGSEGV in H5F__close_cb). vesph closes every object it opens
// itself, so that clean-up would only crash: it is switched off before the library starts.
inline void startHdf5() {
  static const bool started = [] {
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
    return true;
  }();
  (void)started;
}

inline void check(herr_t status, const char* what) {
  if (status < 0) throw std::runtime_error(std::string("HDF5 error: ") + what);
}
inline hid_t checkId(hid_t id, const char* what) {
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
inline constexpr std::size_t kCompactSceneBytes = 32768;

inline void attrString(hid_t loc, const char* name, const std::string& value) {
  Handle type(checkId(H5Tcopy(H5T_C_S1), name), H5Tclose);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  Handle space(checkId(H5Screate(H5S_SCALAR), name), H5Sclose);
  Handle a(checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose);
  check(H5Awrite(a, type, value.empty() ? "" : value.c_str()), name);
}

template <class T>
inline void attrScalar(hid_t loc, const char* name, hid_t type, T value) {
  Handle space(checkId(H5Screate(H5S_SCALAR), name), H5Sclose);
  Handle a(checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name), H5Aclose);
  check(H5Awrite(a, type, &value), name);
}

inline void dataset(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data,
             std::size_t rows, std::size_t cols) {
  hsize_t dims[2] = {rows, cols};
  Handle space(checkId(H5Screate_simple(cols ? 2 : 1, dims, nullptr), name), H5Sclose);
  Handle d(checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name), H5Dclose);
  if (rows) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}

constexpr const char* kDiagColumns[] = {"time", "dt", "kinetic_energy", "mass", "max_speed",
                                        "max_density_deviation"};

inline void writeAtomically(const std::string& path, const std::string& text) {
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
inline void replaceAttrString(hid_t loc, const char* name, const std::string& value) {
  if (H5Aexists(loc, name) > 0) check(H5Adelete(loc, name), name);
  attrString(loc, name, value);
}
template <class T>
inline void replaceAttrScalar(hid_t loc, const char* name, hid_t type, T value) {
  if (H5Aexists(loc, name) > 0) check(H5Adelete(loc, name), name);
  attrScalar<T>(loc, name, type, value);
}

// Reading a file written by someone else (a resumed run's, possibly damaged): every object is
// checked for the rank, shape and type class it is read as before anything is copied, and a
// mismatch is an InputError naming the object ("/checkpoint/state: ..."); the caller adds the file.
inline std::string objectPath(hid_t loc, const char* name) {
  char buf[512] = "";
  const ssize_t len = H5Iget_name(loc, buf, sizeof buf);
  std::string path = len > 0 ? std::string(buf) : std::string("?");
  if (path != "/") path += "/";
  return path + name;
}

[[noreturn]] inline void malformed(hid_t loc, const char* name, const std::string& why) {
  throw InputError(objectPath(loc, name) + ": " + why);
}

// The type class an object of C++ type T is stored as.
template <class T>
inline H5T_class_t storedClass() {
  return std::is_floating_point_v<T> ? H5T_FLOAT : H5T_INTEGER;
}

inline std::string readAttrString(hid_t loc, const char* name) {
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
inline T readAttrScalar(hid_t loc, const char* name, hid_t type) {
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
inline std::size_t datasetRows(hid_t loc, const char* name, std::size_t cols = 0) {
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
inline std::vector<T> readVector(hid_t loc, const char* name, hid_t mem_type) {
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
inline hid_t createExtensible(hid_t group, const char* name, hid_t file_type, hsize_t chunk_rows) {
  hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, chunk[1] = {chunk_rows};
  Handle space(checkId(H5Screate_simple(1, dims, maxdims), name), H5Sclose);
  Handle plist(checkId(H5Pcreate(H5P_DATASET_CREATE), name), H5Pclose);
  H5Pset_chunk(plist, 1, chunk);
  return checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, plist, H5P_DEFAULT), name);
}

// Writes a whole 1-D extensible dataset, created on first use and then overwritten in place:
// the checkpoint does not make the file grow with every frame.
// write = false: the dataset's size only (a process other than the one that writes rows every
// process holds alike, in a file written together).
inline void writeResizable(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t n,
                    hsize_t chunk_rows = 1 << 16, bool write = true) {
  Handle d(H5Lexists(group, name, H5P_DEFAULT) > 0 ? checkId(H5Dopen2(group, name, H5P_DEFAULT), name)
                                                    : createExtensible(group, name, file_type, chunk_rows),
           H5Dclose);
  hsize_t size[1] = {n};
  check(H5Dset_extent(d, size), name);
  if (n && write) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
}


}  // namespace vesph::hdf5io
