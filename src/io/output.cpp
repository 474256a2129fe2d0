#include "vesph/io/output.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "vesph/core/types.hpp"

namespace vesph {
namespace {

void check(herr_t status, const char* what) {
  if (status < 0) throw std::runtime_error(std::string("HDF5 error: ") + what);
}
hid_t checkId(hid_t id, const char* what) {
  if (id < 0) throw std::runtime_error(std::string("HDF5 error: ") + what);
  return id;
}

void attrString(hid_t loc, const char* name, const std::string& value) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, value.empty() ? 1 : value.size());
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name);
  check(H5Awrite(a, type, value.empty() ? "" : value.c_str()), name);
  H5Aclose(a);
  H5Sclose(space);
  H5Tclose(type);
}

template <class T>
void attrScalar(hid_t loc, const char* name, hid_t type, T value) {
  hid_t space = H5Screate(H5S_SCALAR);
  hid_t a = checkId(H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT), name);
  check(H5Awrite(a, type, &value), name);
  H5Aclose(a);
  H5Sclose(space);
}

void dataset(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data,
             std::size_t rows, std::size_t cols) {
  hsize_t dims[2] = {rows, cols};
  hid_t space = H5Screate_simple(cols ? 2 : 1, dims, nullptr);
  hid_t d = checkId(H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
  if (rows) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
  H5Dclose(d);
  H5Sclose(space);
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

std::string readAttrString(hid_t loc, const char* name) {
  if (H5Aexists(loc, name) <= 0) return {};
  hid_t a = checkId(H5Aopen(loc, name, H5P_DEFAULT), name);
  hid_t type = H5Aget_type(a);
  std::string value;
  if (H5Tget_class(type) == H5T_STRING) {
    const std::size_t size = H5Tget_size(type);
    std::vector<char> buf(size + 1, '\0');
    hid_t mem = H5Tcopy(H5T_C_S1);
    H5Tset_size(mem, size + 1);
    if (H5Aread(a, mem, buf.data()) >= 0) value = buf.data();
    H5Tclose(mem);
  }
  H5Tclose(type);
  H5Aclose(a);
  return value;
}
template <class T>
T readAttrScalar(hid_t loc, const char* name, hid_t type) {
  T value{};
  hid_t a = checkId(H5Aopen(loc, name, H5P_DEFAULT), name);
  check(H5Aread(a, type, &value), name);
  H5Aclose(a);
  return value;
}

std::size_t datasetRows(hid_t loc, const char* name) {
  hid_t d = checkId(H5Dopen2(loc, name, H5P_DEFAULT), name);
  hid_t space = H5Dget_space(d);
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space, dims, nullptr);
  H5Sclose(space);
  H5Dclose(d);
  return dims[0];
}

template <class T>
std::vector<T> readVector(hid_t loc, const char* name, hid_t mem_type) {
  std::vector<T> v(datasetRows(loc, name));
  hid_t d = checkId(H5Dopen2(loc, name, H5P_DEFAULT), name);
  if (!v.empty()) check(H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
  H5Dclose(d);
  return v;
}

// An empty 1-D dataset that can grow and shrink (chunked, unlimited): the diagnostics columns
// and the checkpoint's arrays. Returns the open dataset.
hid_t createExtensible(hid_t group, const char* name, hid_t file_type, hsize_t chunk_rows) {
  hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, chunk[1] = {chunk_rows};
  hid_t space = H5Screate_simple(1, dims, maxdims);
  hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(plist, 1, chunk);
  hid_t d = H5Dcreate2(group, name, file_type, space, H5P_DEFAULT, plist, H5P_DEFAULT);
  H5Pclose(plist);
  H5Sclose(space);
  return checkId(d, name);
}

// Writes a whole 1-D extensible dataset, created on first use and then overwritten in place:
// the checkpoint does not make the file grow with every frame.
void writeResizable(hid_t group, const char* name, hid_t file_type, hid_t mem_type, const void* data, std::size_t n,
                    hsize_t chunk_rows = 1 << 16) {
  const hid_t d = H5Lexists(group, name, H5P_DEFAULT) > 0 ? checkId(H5Dopen2(group, name, H5P_DEFAULT), name)
                                                          : createExtensible(group, name, file_type, chunk_rows);
  hsize_t size[1] = {n};
  check(H5Dset_extent(d, size), name);
  if (n) check(H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
  H5Dclose(d);
}

}  // namespace

ResumeSource readResumeSource(const std::string& dir, const std::string& name) {
  const std::string path = (std::filesystem::path(dir) / (name + ".h5")).string();
  if (!std::filesystem::exists(path))
    throw InputError("--resume: nothing to resume: " + path + " does not exist (run without --resume first)");
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) throw InputError("--resume: " + path + " is not a readable HDF5 file");
  ResumeSource r;
  try {
    if (readAttrString(file, "format") != "vesph-1") throw InputError("--resume: " + path + " is not a vesph-1 output file");
    r.scene_toml = readAttrString(file, "scene");
    if (H5Lexists(file, "checkpoint", H5P_DEFAULT) <= 0)
      throw InputError("--resume: " + path + " holds no checkpoint (written by a vesph without --resume support)");
    hid_t g = checkId(H5Gopen2(file, "checkpoint", H5P_DEFAULT), "checkpoint");
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
      hid_t arr = checkId(H5Gopen2(g, "arrays", H5P_DEFAULT), "checkpoint arrays");
      H5G_info_t info;
      check(H5Gget_info(arr, &info), "checkpoint arrays");
      for (hsize_t k = 0; k < info.nlinks; ++k) {
        char aname[256];
        if (H5Lget_name_by_idx(arr, ".", H5_INDEX_NAME, H5_ITER_INC, k, aname, sizeof aname, H5P_DEFAULT) < 0) continue;
        c.arrays.emplace_back(aname, readVector<double>(arr, aname, H5T_NATIVE_DOUBLE));
      }
      H5Gclose(arr);
    }
    H5Gclose(g);
  } catch (...) {
    H5Fclose(file);
    throw;
  }
  H5Fclose(file);
  return r;
}

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs,
                              double resume_time)
    : dir_(dir), name_(name), extra_columns_(attrs.extra_columns) {
  h5_path_ = (std::filesystem::path(dir) / (name + ".h5")).string();
  xdmf_path_ = (std::filesystem::path(dir) / (name + ".xdmf")).string();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  file_ = H5Fopen(h5_path_.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  if (file_ < 0) throw std::runtime_error("cannot open " + h5_path_ + " for writing");
  replaceAttrString(file_, "scene", attrs.scene_toml);
  // Frames up to the checkpoint stay; later ones (none when the checkpoint is the last frame,
  // as vesph writes it) are removed. A frame's time may differ from resume_time by rounding.
  const double tol = 1e-12 * std::max(1.0, std::abs(resume_time));
  hid_t frames = checkId(H5Gopen2(file_, "frames", H5P_DEFAULT), "frames");
  for (std::size_t k = 0;; ++k) {
    char gname[32];
    std::snprintf(gname, sizeof gname, "%06zu", k);
    if (H5Lexists(frames, gname, H5P_DEFAULT) <= 0) break;
    hid_t g = checkId(H5Gopen2(frames, gname, H5P_DEFAULT), gname);
    const double t = readAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE);
    FrameInfo info{gname, t, datasetRows(g, "id"), H5Lexists(g, "extra_stress", H5P_DEFAULT) > 0,
                   H5Lexists(g, "free_surface", H5P_DEFAULT) > 0, H5Lexists(g, "pressure", H5P_DEFAULT) > 0,
                   H5Lexists(g, "extra_stress_zz", H5P_DEFAULT) > 0};
    H5Gclose(g);
    if (t > resume_time + tol) check(H5Ldelete(frames, gname, H5P_DEFAULT), "remove a frame after the checkpoint");
    else frames_.push_back(info);
  }
  H5Gclose(frames);
  // Diagnostics rows after the checkpoint's time are dropped from every column.
  hid_t diag = checkId(H5Gopen2(file_, "diagnostics", H5P_DEFAULT), "diagnostics");
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
    hid_t d = checkId(H5Dopen2(diag, col.c_str(), H5P_DEFAULT), col.c_str());
    hsize_t size[1] = {diag_rows_};
    check(H5Dset_extent(d, size), "truncate diagnostics");
    H5Dclose(d);
  }
  H5Gclose(diag);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush");
  writeXdmf();
}

template <int D>
void OutputWriter<D>::writeCheckpoint(const Checkpoint& c) {
  hid_t g = H5Lexists(file_, "checkpoint", H5P_DEFAULT) > 0
                ? checkId(H5Gopen2(file_, "checkpoint", H5P_DEFAULT), "checkpoint")
                : checkId(H5Gcreate2(file_, "checkpoint", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint");
  writeResizable(g, "state", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.state.data(), c.state.size());
  writeResizable(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, c.id.data(), c.id.size());
  if (!c.arrays.empty()) {
    hid_t arr = H5Lexists(g, "arrays", H5P_DEFAULT) > 0
                    ? checkId(H5Gopen2(g, "arrays", H5P_DEFAULT), "checkpoint arrays")
                    : checkId(H5Gcreate2(g, "arrays", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "checkpoint arrays");
    for (const auto& [aname, values] : c.arrays)
      writeResizable(arr, aname.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size());
    H5Gclose(arr);
  }
  replaceAttrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, c.step);
  replaceAttrScalar<std::uint64_t>(g, "rhs_evals", H5T_NATIVE_UINT64, c.rhs_evals);
  replaceAttrScalar<std::uint64_t>(g, "rejected_steps", H5T_NATIVE_UINT64, c.rejected_steps);
  replaceAttrScalar<std::uint64_t>(g, "neighbour_builds", H5T_NATIVE_UINT64, c.neighbour_builds);
  replaceAttrScalar<double>(g, "wall_seconds", H5T_NATIVE_DOUBLE, c.wall_seconds);
  replaceAttrScalar<double>(g, "max_density_deviation", H5T_NATIVE_DOUBLE, c.max_density_deviation);
  replaceAttrScalar<std::uint64_t>(g, "resumes", H5T_NATIVE_UINT64, c.resumes);
  replaceAttrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, c.time);
  H5Gclose(g);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush");
}

template <int D>
OutputWriter<D>::OutputWriter(const std::string& dir, const std::string& name, const FileAttributes& attrs)
    : dir_(dir), name_(name), extra_columns_(attrs.extra_columns) {
  if (extra_columns_.size() > kMaxExtraDiagnostics) throw std::logic_error("too many extra diagnostics columns");
  std::filesystem::create_directories(dir);
  h5_path_ = (std::filesystem::path(dir) / (name + ".h5")).string();
  xdmf_path_ = (std::filesystem::path(dir) / (name + ".xdmf")).string();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
  file_ = H5Fcreate(h5_path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) throw std::runtime_error("cannot create " + h5_path_);
  attrString(file_, "format", "vesph-1");
  attrScalar<int>(file_, "dim", H5T_NATIVE_INT, attrs.dim);
  attrString(file_, "scene", attrs.scene_toml);
  attrScalar<double>(file_, "dx", H5T_NATIVE_DOUBLE, attrs.dx);
  attrScalar<double>(file_, "h", H5T_NATIVE_DOUBLE, attrs.h);
  attrString(file_, "kernel", attrs.kernel);
  H5Gclose(checkId(H5Gcreate2(file_, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frames"));
  hid_t diag = checkId(H5Gcreate2(file_, "diagnostics", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "diagnostics");
  std::vector<const char*> columns(std::begin(kDiagColumns), std::end(kDiagColumns));
  for (const std::string& c : extra_columns_) columns.push_back(c.c_str());
  for (const char* col : columns) H5Dclose(createExtensible(diag, col, H5T_IEEE_F64LE, 4096));
  H5Gclose(diag);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush");
}

template <int D>
OutputWriter<D>::~OutputWriter() {
  if (file_ >= 0) H5Fclose(file_);
}

template <int D>
void OutputWriter<D>::appendDiagnostics(const std::vector<DiagnosticsRow>& rows) {
  if (rows.empty()) return;
  hid_t diag = checkId(H5Gopen2(file_, "diagnostics", H5P_DEFAULT), "diagnostics");
  std::vector<double> col(rows.size());
  const std::size_t base = std::size(kDiagColumns);
  for (std::size_t c = 0; c < base + extra_columns_.size(); ++c) {
    for (std::size_t r = 0; r < rows.size(); ++r) col[r] = c < base ? (&rows[r].time)[c] : rows[r].extra[c - base];
    const char* cname = c < base ? kDiagColumns[c] : extra_columns_[c - base].c_str();
    hid_t d = checkId(H5Dopen2(diag, cname, H5P_DEFAULT), cname);
    hsize_t newsize[1] = {diag_rows_ + rows.size()};
    check(H5Dset_extent(d, newsize), "extend diagnostics");
    hid_t fspace = H5Dget_space(d);
    hsize_t offset[1] = {diag_rows_}, count[1] = {rows.size()};
    H5Sselect_hyperslab(fspace, H5S_SELECT_SET, offset, nullptr, count, nullptr);
    hid_t mspace = H5Screate_simple(1, count, nullptr);
    check(H5Dwrite(d, H5T_NATIVE_DOUBLE, mspace, fspace, H5P_DEFAULT, col.data()), "diagnostics");
    H5Sclose(mspace);
    H5Sclose(fspace);
    H5Dclose(d);
  }
  H5Gclose(diag);
  diag_rows_ += rows.size();
}

template <int D>
void OutputWriter<D>::writeFrame(double time, std::int64_t step, const ParticleSet<D>& p,
                                 const std::vector<DiagnosticsRow>& new_rows) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu", frames_.size());
  const std::string group_path = std::string("/frames/") + name;
  hid_t g = checkId(H5Gcreate2(file_, group_path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "frame");
  attrScalar<double>(g, "time", H5T_NATIVE_DOUBLE, time);
  attrScalar<std::int64_t>(g, "step", H5T_NATIVE_INT64, step);
  const std::size_t n = p.size();
  dataset(g, "id", H5T_STD_U64LE, H5T_NATIVE_UINT64, p.id.data(), n, 0);
  dataset(g, "kind", H5T_STD_U8LE, H5T_NATIVE_UINT8, p.kind.data(), n, 0);
  dataset(g, "position", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.position.data(), n, D);
  dataset(g, "velocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.velocity.data(), n, D);
  dataset(g, "density", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.density.data(), n, 0);
  dataset(g, "mass", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, p.mass.data(), n, 0);
  FrameInfo info{name, time, n, false, false, false, false};
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
  H5Gclose(g);
  appendDiagnostics(new_rows);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush");
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
