#include "vesph/parallel/space_partition.hpp"

#include <zoltan.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vesph {
namespace {

// What Zoltan's query callbacks read: this rank's particles.
struct ZoltanInput {
  std::span<const double> positions, weights;
  int dimension = 0;
  int rank = 0;
};

int numberOfObjects(void* data, int* ierr) {
  const auto* in = static_cast<const ZoltanInput*>(data);
  *ierr = ZOLTAN_OK;
  return static_cast<int>(in->weights.size());
}

void objectList(void* data, int, int, ZOLTAN_ID_PTR global_ids, ZOLTAN_ID_PTR local_ids, int wdim, float* weights,
                int* ierr) {
  const auto* in = static_cast<const ZoltanInput*>(data);
  const int rank = in->rank;
  for (std::size_t i = 0; i < in->weights.size(); ++i) {
    // Global ids of two entries (rank, local index): unique without knowing the particles' ids,
    // and within ZOLTAN_ID_TYPE (unsigned int on Debian's build) whatever the particle count.
    global_ids[2 * i] = static_cast<ZOLTAN_ID_TYPE>(rank);
    global_ids[2 * i + 1] = static_cast<ZOLTAN_ID_TYPE>(i);
    local_ids[i] = static_cast<ZOLTAN_ID_TYPE>(i);
    if (wdim == 1) weights[i] = static_cast<float>(in->weights[i]);
  }
  *ierr = ZOLTAN_OK;
}

int numberOfDimensions(void* data, int* ierr) {
  *ierr = ZOLTAN_OK;
  return static_cast<const ZoltanInput*>(data)->dimension;
}

void coordinates(void* data, int, int, int n, ZOLTAN_ID_PTR, ZOLTAN_ID_PTR local_ids, int dim, double* out,
                 int* ierr) {
  const auto* in = static_cast<const ZoltanInput*>(data);
  for (int k = 0; k < n; ++k) {
    const std::size_t i = local_ids[k];
    for (int a = 0; a < dim; ++a) out[dim * k + a] = in->positions[static_cast<std::size_t>(dim) * i + a];
  }
  *ierr = ZOLTAN_OK;
}

void checkZoltan(int code, const char* what) {
  if (code != ZOLTAN_OK && code != ZOLTAN_WARN) throw std::runtime_error(std::string("Zoltan: ") + what + " failed");
}

}  // namespace

template <int D>
double distanceToBox(const Domain<D>& domain, const double* x, const Box<D>& box) {
  double d2 = 0;
  for (int a = 0; a < D; ++a) {
    auto gap = [&](double y) { return std::max({box.lo[a] - y, 0.0, y - box.hi[a]}); };
    double g = gap(x[a]);
    if (domain.periodic[a]) {
      const double L = domain.length(a);
      g = std::min({g, gap(x[a] + L), gap(x[a] - L)});
    }
    d2 += g * g;
  }
  return std::sqrt(d2);
}

template <int D>
double distanceBetweenBoxes(const Domain<D>& domain, const Box<D>& a, const Box<D>& b) {
  double d2 = 0;
  for (int k = 0; k < D; ++k) {
    auto gap = [&](double shift) { return std::max({a.lo[k] - (b.hi[k] + shift), 0.0, (b.lo[k] + shift) - a.hi[k]}); };
    double g = gap(0.0);
    if (domain.periodic[k]) {
      const double L = domain.length(k);
      g = std::min({g, gap(L), gap(-L)});
    }
    d2 += g * g;
  }
  return std::sqrt(d2);
}

template <int D>
SpacePartition<D>::SpacePartition(const Communicator& comm, const Domain<D>& domain, double imbalance_tolerance)
    : comm_(comm), domain_(domain) {
  if (!(imbalance_tolerance >= 1.0)) throw std::invalid_argument("SpacePartition: imbalance tolerance below 1");
  static bool zoltan_started = [] {
    float version = 0;
    checkZoltan(Zoltan_Initialize(0, nullptr, &version), "Zoltan_Initialize");
    return true;
  }();
  (void)zoltan_started;
  zz_ = Zoltan_Create(comm_.handle());
  if (zz_ == nullptr) throw std::runtime_error("Zoltan: Zoltan_Create failed");
  const std::string tolerance = std::to_string(imbalance_tolerance);
  const std::pair<const char*, const char*> params[] = {
      {"DEBUG_LEVEL", "0"},       {"LB_METHOD", "RCB"},          {"NUM_GID_ENTRIES", "2"},
      {"NUM_LID_ENTRIES", "1"},   {"OBJ_WEIGHT_DIM", "1"},       {"RETURN_LISTS", "EXPORT"},
      {"KEEP_CUTS", "1"},         {"RCB_REUSE", "1"},            {"IMBALANCE_TOL", tolerance.c_str()},
      {"RCB_OUTPUT_LEVEL", "0"},  {"CHECK_GEOM", "1"}};
  for (const auto& [key, value] : params) checkZoltan(Zoltan_Set_Param(zz_, key, value), key);
}

template <int D>
SpacePartition<D>::~SpacePartition() {
  if (zz_ != nullptr) Zoltan_Destroy(&zz_);
}

template <int D>
std::vector<int> SpacePartition<D>::partition(std::span<const double> positions, std::span<const double> weights) {
  if (positions.size() != weights.size() * D) throw std::invalid_argument("SpacePartition: positions and weights disagree");
  ZoltanInput input{positions, weights, D, comm_.rank()};
  Zoltan_Set_Num_Obj_Fn(zz_, numberOfObjects, &input);
  Zoltan_Set_Obj_List_Fn(zz_, objectList, &input);
  Zoltan_Set_Num_Geom_Fn(zz_, numberOfDimensions, &input);
  Zoltan_Set_Geom_Multi_Fn(zz_, coordinates, &input);
  int changes = 0, gid_entries = 0, lid_entries = 0, n_import = 0, n_export = 0;
  ZOLTAN_ID_PTR import_gids = nullptr, import_lids = nullptr, export_gids = nullptr, export_lids = nullptr;
  int *import_procs = nullptr, *import_parts = nullptr, *export_procs = nullptr, *export_parts = nullptr;
  checkZoltan(Zoltan_LB_Partition(zz_, &changes, &gid_entries, &lid_entries, &n_import, &import_gids, &import_lids,
                                  &import_procs, &import_parts, &n_export, &export_gids, &export_lids, &export_procs,
                                  &export_parts),
              "Zoltan_LB_Partition");
  std::vector<int> destination(weights.size(), comm_.rank());
  for (int k = 0; k < n_export; ++k) destination[export_lids[k]] = export_procs[k];
  Zoltan_LB_Free_Part(&import_gids, &import_lids, &import_procs, &import_parts);
  Zoltan_LB_Free_Part(&export_gids, &export_lids, &export_procs, &export_parts);
  // The callbacks' data lives on this stack frame only.
  Zoltan_Set_Num_Obj_Fn(zz_, nullptr, nullptr);
  Zoltan_Set_Obj_List_Fn(zz_, nullptr, nullptr);
  Zoltan_Set_Num_Geom_Fn(zz_, nullptr, nullptr);
  Zoltan_Set_Geom_Multi_Fn(zz_, nullptr, nullptr);

  boxes_.assign(static_cast<std::size_t>(comm_.size()), Box<D>{});
  // One rank: Zoltan keeps no cuts, and the one box is everything.
  if (comm_.size() == 1) {
    for (int a = 0; a < D; ++a) {
      boxes_[0].lo[a] = domain_.periodic[a] ? domain_.lo[a] : -std::numeric_limits<double>::max();
      boxes_[0].hi[a] = domain_.periodic[a] ? domain_.hi[a] : std::numeric_limits<double>::max();
    }
    ++partitions_;
    return destination;
  }
  for (int part = 0; part < comm_.size(); ++part) {
    int ndim = 0;
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    checkZoltan(Zoltan_RCB_Box(zz_, part, &ndim, &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2]), "Zoltan_RCB_Box");
    Box<D>& box = boxes_[static_cast<std::size_t>(part)];
    for (int a = 0; a < D; ++a) {
      box.lo[a] = lo[a];
      box.hi[a] = hi[a];
      // A periodic axis has no outside: an outer box ends at the domain's edge, so that the
      // periodic distance to it is finite. Non-periodic axes keep the open ends (a particle
      // past the domain's bounds still has an owner until the domain exit removes it).
      if (domain_.periodic[a]) {
        box.lo[a] = std::max(box.lo[a], domain_.lo[a]);
        box.hi[a] = std::min(box.hi[a], domain_.hi[a]);
      } else {
        box.lo[a] = std::max(box.lo[a], -std::numeric_limits<double>::max());
        box.hi[a] = std::min(box.hi[a], std::numeric_limits<double>::max());
      }
    }
  }
  ++partitions_;
  // RCB may split particles of one coordinate across a cut to even the weights; ownership is
  // the cuts' (owner()), so that a particle on a cut has the owner the next migration gives it.
  for (std::size_t i = 0; i < destination.size(); ++i) destination[i] = owner(positions.data() + D * i);
  return destination;
}

template <int D>
int SpacePartition<D>::owner(const double* x) const {
  if (partitions_ == 0) throw std::logic_error("SpacePartition::owner before the first partition");
  if (comm_.size() == 1) return 0;
  double p[3] = {0, 0, 0};
  for (int a = 0; a < D; ++a) p[a] = x[a];
  int proc = -1;
  checkZoltan(Zoltan_LB_Point_Assign(zz_, p, &proc), "Zoltan_LB_Point_Assign");
  return proc;
}

template double distanceToBox<2>(const Domain<2>&, const double*, const Box<2>&);
template double distanceToBox<3>(const Domain<3>&, const double*, const Box<3>&);
template double distanceBetweenBoxes<2>(const Domain<2>&, const Box<2>&, const Box<2>&);
template double distanceBetweenBoxes<3>(const Domain<3>&, const Box<3>&, const Box<3>&);
template class SpacePartition<2>;
template class SpacePartition<3>;

}  // namespace vesph
