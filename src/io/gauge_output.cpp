// The gauges' series in the output file (docs/user-guide.md "Output", an extension of vesph-1
// that readers of the frames ignore): /gauges/<name> is a group with the attributes type
// (string) and position (float64 array, m; absent for a front gauge) and one extensible 1-D
// float64 dataset per column, "time" first, one row per frame. Files of scenes without gauges
// have no /gauges group.
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "vesph/io/output.hpp"
#include "hdf5_support.hpp"

namespace vesph {
using namespace hdf5io;

template <int D>
void OutputWriter<D>::createGauges() {
  if (gauges_.empty()) return;
  Handle root(checkId(H5Gcreate2(file_, "gauges", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "gauges"), H5Gclose);
  for (const GaugeSeries& g : gauges_) {
    Handle grp(checkId(H5Gcreate2(root, g.name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), g.name.c_str()),
               H5Gclose);
    attrString(grp, "type", g.type);
    if (!g.position.empty()) {
      hsize_t n[1] = {g.position.size()};
      Handle space(checkId(H5Screate_simple(1, n, nullptr), "position"), H5Sclose);
      Handle a(checkId(H5Acreate2(grp, "position", H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), "position"),
               H5Aclose);
      check(H5Awrite(a, H5T_NATIVE_DOUBLE, g.position.data()), "position");
    }
    for (const std::string& col : g.columns) H5Dclose(createExtensible(grp, col.c_str(), H5T_IEEE_F64LE, 1024));
  }
  gauge_rows_ = 0;
}

template <int D>
void OutputWriter<D>::truncateGauges(double resume_time) {
  if (gauges_.empty()) return;
  if (H5Lexists(file_, "gauges", H5P_DEFAULT) <= 0) {
    // A file written without gauges cannot be resumed with them (the scenes differ); kept for a
    // file whose group was lost: the series starts again at the resumed frames.
    createGauges();
    return;
  }
  Handle root(checkId(H5Gopen2(file_, "gauges", H5P_DEFAULT), "gauges"), H5Gclose);
  const double tol = 1e-12 * std::max(1.0, std::abs(resume_time));
  std::size_t keep = 0;
  for (std::size_t k = 0; k < gauges_.size(); ++k) {
    const GaugeSeries& g = gauges_[k];
    if (H5Lexists(root, g.name.c_str(), H5P_DEFAULT) <= 0) malformed(root, g.name.c_str(), "missing");
    Handle grp(checkId(H5Gopen2(root, g.name.c_str(), H5P_DEFAULT), g.name.c_str()), H5Gclose);
    const std::vector<double> times = readVector<double>(grp, "time", H5T_NATIVE_DOUBLE);
    std::size_t rows = 0;
    while (rows < times.size() && times[rows] <= resume_time + tol) ++rows;
    if (k == 0) keep = rows;
    else if (rows != keep) malformed(root, g.name.c_str(), "a row count unlike the other gauges'");
    for (const std::string& col : g.columns) {
      datasetRows(grp, col.c_str());  // rank 1, or malformed
      Handle d(checkId(H5Dopen2(grp, col.c_str(), H5P_DEFAULT), col.c_str()), H5Dclose);
      hsize_t size[1] = {rows};
      check(H5Dset_extent(d, size), "truncate gauges");
    }
  }
  gauge_rows_ = keep;
}

template <int D>
void OutputWriter<D>::appendGauges(const std::vector<std::vector<double>>& rows) {
  if (gauges_.empty()) return;
  if (file_ < 0) throw std::runtime_error("cannot write to " + h5_path_ + " after an earlier error");
  if (rows.size() != gauges_.size()) throw std::logic_error("appendGauges: one row per gauge");
  bool written = true;
  try {
    Handle root(checkId(H5Gopen2(file_, "gauges", H5P_DEFAULT), "gauges"), H5Gclose);
    for (std::size_t k = 0; k < gauges_.size(); ++k) {
      const GaugeSeries& g = gauges_[k];
      if (rows[k].size() != g.columns.size()) throw std::logic_error("appendGauges: one value per column");
      Handle grp(checkId(H5Gopen2(root, g.name.c_str(), H5P_DEFAULT), g.name.c_str()), H5Gclose);
      for (std::size_t c = 0; c < g.columns.size(); ++c) {
        const char* cname = g.columns[c].c_str();
        Handle d(checkId(H5Dopen2(grp, cname, H5P_DEFAULT), cname), H5Dclose);
        hsize_t newsize[1] = {gauge_rows_ + 1};
        check(H5Dset_extent(d, newsize), "extend gauges");
        Handle fspace(checkId(H5Dget_space(d), cname), H5Sclose);
        hsize_t offset[1] = {gauge_rows_}, count[1] = {1};
        H5Sselect_hyperslab(fspace, H5S_SELECT_SET, offset, nullptr, count, nullptr);
        Handle mspace(checkId(H5Screate_simple(1, count, nullptr), cname), H5Sclose);
        writeSharedRows(d, mspace, fspace, &rows[k][c], "gauges");
      }
    }
  } catch (const std::runtime_error&) {
    written = false;
  }
  if (!agreed(written)) failed("the gauges");
  ++gauge_rows_;
}

template void OutputWriter<2>::createGauges();
template void OutputWriter<3>::createGauges();
template void OutputWriter<2>::truncateGauges(double);
template void OutputWriter<3>::truncateGauges(double);
template void OutputWriter<2>::appendGauges(const std::vector<std::vector<double>>&);
template void OutputWriter<3>::appendGauges(const std::vector<std::vector<double>>&);

}  // namespace vesph
