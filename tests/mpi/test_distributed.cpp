// The distributed particle layer (parallel/: Zoltan's partition, migration, the halo) under 1,
// 2 and 4 ranks (ctest mpi.np1, mpi.np2, mpi.np4; oversubscribed on a 2-core machine). Every
// rank builds the same whole particle set, keeps a scattered share of it (particle k on rank
// k mod size: the worst start, every particle far from its box), then partitions and migrates;
// the serial results over the whole set are the reference.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <vector>

#include "vesph/core/neighbours.hpp"
#include "vesph/core/pair_loop.hpp"
#include "vesph/io/output.hpp"
#include "vesph/isph/linear_solver.hpp"
#include "vesph/parallel/particle_exchange.hpp"

namespace vesph {
namespace {

constexpr double kDx = 0.01, kRho = 1000.0;

double tagOf(std::uint64_t id) { return 0.25 * static_cast<double>(id) + 1.0; }
Vec<2> velocityOf(std::uint64_t id, double t) { return Vec<2>(std::sin(0.1 * id + t), std::cos(0.07 * id - t)); }

// n x m jittered fluid lattice from the origin, then two rows of wall particles below it
// (non-periodic) — the whole set every rank starts from. Fields of every range travel with it.
template <int D>
ParticleSet<D> wholeSet(const std::array<int, D>& n, bool walls, unsigned seed) {
  ParticleSet<D> p;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.2 * kDx, 0.2 * kDx);
  std::size_t total = 1;
  for (int a = 0; a < D; ++a) total *= static_cast<std::size_t>(n[a]);
  std::uint64_t id = 0;
  for (std::size_t c = 0; c < total; ++c) {
    std::size_t rem = c;
    Vec<D> x;
    for (int a = 0; a < D; ++a) {
      x[a] = (static_cast<double>(rem % static_cast<std::size_t>(n[a])) + 0.5) * kDx + jitter(rng);
      rem /= static_cast<std::size_t>(n[a]);
    }
    p.add(x, Vec<D>::Zero(), kRho * (1.0 + 0.01 * std::sin(static_cast<double>(id))), kRho * std::pow(kDx, D),
          ParticleKind::fluid, id);
    ++id;
  }
  if (walls)
    for (int row = 1; row <= 2; ++row)
      for (int i = 0; i < n[0]; ++i) {
        Vec<D> x = Vec<D>::Constant(0.5 * kDx);
        x[0] = (i + 0.5) * kDx;
        x[D - 1] = -(row - 0.5) * kDx;
        p.add(x, Vec<D>::Zero(), kRho, kRho * std::pow(kDx, D), row == 1 ? ParticleKind::wall : ParticleKind::dummy, id++);
      }
  p.fields.require("moving_tag", 2, Field::Range::moving);
  p.fields.require("fixed_tag", 1, Field::Range::fixed);
  p.fields.require("every_tag", 1, Field::Range::all);
  p.resizeFields();
  Field& mt = *p.fields.find("moving_tag");
  Field& ft = *p.fields.find("fixed_tag");
  Field& et = *p.fields.find("every_tag");
  for (std::size_t i = 0; i < p.size(); ++i) {
    et.at(i)[0] = tagOf(p.id[i]);
    if (i < p.n_moving) {
      mt.at(i)[0] = tagOf(p.id[i]);
      mt.at(i)[1] = -tagOf(p.id[i]);
    } else {
      ft.at(i - p.n_moving)[0] = 2.0 * tagOf(p.id[i]);
    }
  }
  return p;
}

// Particle k of the whole set on rank k mod size.
template <int D>
ParticleSet<D> scatteredShare(const ParticleSet<D>& whole, const Communicator& comm) {
  std::vector<int> dest(whole.size());
  for (std::size_t i = 0; i < whole.size(); ++i) dest[i] = static_cast<int>(i % static_cast<std::size_t>(comm.size()));
  ParticleSet<D> mine;
  mine.fields = FieldStore{};
  for (const auto& f : whole.fields.all()) mine.fields.require(f->name, f->components, f->range);
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < whole.size(); ++i)
    if (dest[i] == comm.rank()) keep.push_back(i);
  for (std::size_t i : keep) {
    Vec<D> x = whole.x(i), v = whole.v(i);
    mine.add(x, v, whole.density[i], whole.mass[i], static_cast<ParticleKind>(whole.kind[i]), whole.id[i]);
  }
  mine.resizeFields();
  for (const auto& f : whole.fields.all()) {
    Field& g = *mine.fields.find(f->name);
    for (std::size_t k = 0; k < keep.size(); ++k) {
      const std::size_t i = keep[k];
      const bool moving = i < whole.n_moving;
      if (f->range == Field::Range::moving && !moving) continue;
      if (f->range == Field::Range::fixed && moving) continue;
      const std::size_t from = f->range == Field::Range::fixed ? i - whole.n_moving : i;
      const std::size_t to = f->range == Field::Range::fixed ? k - mine.n_moving : k;
      std::copy_n(f->at(from), f->components, g.at(to));
    }
  }
  return mine;
}

template <int D>
std::vector<double> weightsOf(const ParticleSet<D>& p) {
  std::vector<double> w(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) w[i] = i < p.n_moving ? 1.0 : 0.25;
  return w;
}

// Checks what a migration must leave: every particle once, owned where its box is, moving
// before fixed, its fields with it.
template <int D>
void checkOwnership(const ParticleSet<D>& p, const ParticleSet<D>& whole, const Communicator& comm,
                    const Domain<D>& domain, const SpacePartition<D>& part) {
  REQUIRE(comm.sum(static_cast<std::uint64_t>(p.size())) == whole.size());
  REQUIRE(comm.sum(static_cast<std::uint64_t>(p.n_moving)) == whole.n_moving);
  std::vector<int> counts(static_cast<std::size_t>(comm.size())), at(static_cast<std::size_t>(comm.size()));
  const int mine = static_cast<int>(p.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm.handle());
  for (std::size_t r = 1; r < counts.size(); ++r) at[r] = at[r - 1] + counts[r - 1];
  std::vector<std::uint64_t> ids(whole.size());
  MPI_Allgatherv(p.id.data(), mine, MPI_UINT64_T, ids.data(), counts.data(), at.data(), MPI_UINT64_T, comm.handle());
  std::sort(ids.begin(), ids.end());
  CHECK(std::adjacent_find(ids.begin(), ids.end()) == ids.end());
  CHECK(ids.front() == 0);
  CHECK(ids.back() == whole.size() - 1);
  const Box<D>& box = part.boxes()[static_cast<std::size_t>(comm.rank())];
  const Field& mt = *p.fields.find("moving_tag");
  const Field& ft = *p.fields.find("fixed_tag");
  const Field& et = *p.fields.find("every_tag");
  std::size_t misplaced = 0, wrong_kind = 0, wrong_field = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (distanceToBox(domain, p.position.data() + D * i, box) > 0.0) ++misplaced;
    if (part.owner(p.position.data() + D * i) != comm.rank()) ++misplaced;
    const bool moving = i < p.n_moving;
    if ((p.kind[i] == static_cast<std::uint8_t>(ParticleKind::fluid)) != moving) ++wrong_kind;
    const double t = tagOf(p.id[i]);
    if (et.at(i)[0] != t) ++wrong_field;
    if (moving && (mt.at(i)[0] != t || mt.at(i)[1] != -t)) ++wrong_field;
    if (!moving && ft.at(i - p.n_moving)[0] != 2.0 * t) ++wrong_field;
    if (p.mass[i] != kRho * std::pow(kDx, D)) ++wrong_field;
  }
  CHECK(misplaced == 0);
  CHECK(wrong_kind == 0);
  CHECK(wrong_field == 0);
}

// The SPH density sum rho_i = sum_j m_j W_ij (self included) of the first n particles.
template <int D>
std::map<std::uint64_t, double> densitySum(const ParticleSet<D>& p, std::size_t n, const Domain<D>& domain,
                                           const Kernel& kernel) {
  NeighbourList<D> list;
  list.configure(domain, kernel.supportRadius(), 0.1 * kDx);
  list.update(p, true);
  PairLoop<D> loop;
  std::vector<double> sum(p.n_moving, 0.0);
  loop.forEachMoving(p, kernel, domain, list, true,
                     [&](Index i, std::span<const Neighbour<D>> moving, std::span<const Neighbour<D>> fixed) {
                       double s = p.mass[i] * kernel.W(0.0);
                       for (const auto& nb : moving) s += p.mass[nb.j] * nb.W;
                       for (const auto& nb : fixed) s += p.mass[nb.j] * nb.W;
                       sum[i] = s;
                     });
  std::map<std::uint64_t, double> out;
  for (std::size_t i = 0; i < n; ++i) out[p.id[i]] = sum[i];
  return out;
}

template <int D>
void checkHaloDensities(const std::array<int, D>& n, bool walls, bool periodic_x) {
  const Communicator comm = Communicator::world();
  Domain<D> domain;
  for (int a = 0; a < D; ++a) {
    domain.lo[a] = -0.05;
    domain.hi[a] = n[a] * kDx + 0.05;
  }
  if (periodic_x) {
    domain.lo[0] = 0.0;
    domain.hi[0] = n[0] * kDx;
    domain.periodic[0] = true;
  }
  ParticleSet<D> whole = wholeSet<D>(n, walls, 17);
  for (std::size_t i = 0; i < whole.size(); ++i) whole.position[D * i] = domain.wrap(0, whole.position[D * i]);
  const Kernel kernel(KernelType::quintic, D, 1.3 * kDx);
  const auto reference = densitySum(whole, whole.n_moving, domain, kernel);

  ParticleSet<D> p = scatteredShare(whole, comm);
  SpacePartition<D> part(comm, domain);
  const std::vector<double> w = weightsOf(p);
  ParticleExchange<D> exchange(comm, domain);
  exchange.migrate(p, part.partition(p.position, w));
  checkOwnership(p, whole, comm, domain, part);
  const std::vector<double> w_after = weightsOf(p);
  double load = 0;
  for (double x : w_after) load += x;
  const double imbalance = loadImbalance(comm, load);
  MESSAGE("ranks " << comm.size() << ": load imbalance " << imbalance);
  CHECK(imbalance < 1.1);

  const double radius = kernel.supportRadius() + 0.1 * kDx;
  exchange.buildHalo(p, part.boxes(), radius);
  const HaloLayout& L = exchange.layout();
  CHECK(p.n_moving == L.owned_moving + L.ghost_moving);
  CHECK(p.size() == L.owned_moving + L.ghost_moving + L.owned_fixed + L.ghost_fixed);
  if (comm.size() == 1) CHECK(L.ghosts() == 0);
  else CHECK(L.ghosts() > 0);
  // Ghosts: another rank's particles, each once, none of them this rank's.
  std::vector<std::uint64_t> ghost_ids;
  for (std::size_t i = L.owned_moving; i < p.n_moving; ++i) ghost_ids.push_back(p.id[i]);
  for (std::size_t i = p.n_moving + L.owned_fixed; i < p.size(); ++i) ghost_ids.push_back(p.id[i]);
  std::sort(ghost_ids.begin(), ghost_ids.end());
  CHECK(std::adjacent_find(ghost_ids.begin(), ghost_ids.end()) == ghost_ids.end());
  std::size_t own_as_ghost = 0;
  for (std::size_t i = 0; i < L.owned_moving; ++i) own_as_ghost += std::binary_search(ghost_ids.begin(), ghost_ids.end(), p.id[i]);
  CHECK(own_as_ghost == 0);

  const auto distributed = densitySum(p, L.owned_moving, domain, kernel);
  double worst = 0;
  std::size_t missing = 0;
  for (const auto& [id, rho] : distributed) {
    auto it = reference.find(id);
    if (it == reference.end()) { ++missing; continue; }
    worst = std::max(worst, std::abs(rho - it->second) / it->second);
  }
  CHECK(missing == 0);
  CHECK(comm.max(worst) < 1e-13);

  // The refresh carries the owners' new values to the ghosts.
  Field& mt = *p.fields.find("moving_tag");
  Field& ft = *p.fields.find("fixed_tag");
  for (std::size_t i = 0; i < L.owned_moving; ++i) {
    for (int a = 0; a < D; ++a) p.velocity[D * i + a] = std::sin(0.1 * p.id[i] + a);
    mt.at(i)[0] = 3.0 * tagOf(p.id[i]);
  }
  // A fixed-range field's value of fixed particle i lies at i - n_moving: the owned fixed ones first.
  for (std::size_t f = 0; f < L.owned_fixed; ++f) ft.at(f)[0] = 5.0 * tagOf(p.id[p.n_moving + f]);
  const std::vector<HaloArray> arrays{{p.velocity.data(), D, Field::Range::all},
                                      {mt.data.data(), 2, Field::Range::moving},
                                      {ft.data.data(), 1, Field::Range::fixed}};
  exchange.refresh(arrays);
  std::size_t stale = 0;
  for (std::size_t i = L.owned_moving; i < p.n_moving; ++i) {
    for (int a = 0; a < D; ++a) stale += p.velocity[D * i + a] != std::sin(0.1 * p.id[i] + a);
    stale += mt.at(i)[0] != 3.0 * tagOf(p.id[i]);
  }
  for (std::size_t i = p.n_moving + L.owned_fixed; i < p.size(); ++i) stale += ft.at(i - p.n_moving)[0] != 5.0 * tagOf(p.id[i]);
  CHECK(stale == 0);
  for (std::size_t i = 0; i < L.owned_moving; ++i) mt.at(i)[0] = tagOf(p.id[i]);
  for (std::size_t f = 0; f < L.owned_fixed; ++f) ft.at(f)[0] = 2.0 * tagOf(p.id[p.n_moving + f]);
  CHECK(exchange.counters().refreshes == 1);
  CHECK(exchange.counters().messages_sent == exchange.neighbourRanks().size());

  // The particles move (a shear), leave their boxes, and go to their new owners by the kept
  // cuts; then a repartition evens the load again.
  exchange.removeHalo(p);
  CHECK(p.size() == L.owned_moving + L.owned_fixed);
  for (std::size_t i = 0; i < p.n_moving; ++i) {
    p.position[D * i] += 0.3 * n[0] * kDx * (p.position[D * i + 1] / (n[1] * kDx));
    p.position[D * i] = periodic_x ? domain.wrap(0, p.position[D * i]) : p.position[D * i];
  }
  std::vector<int> dest(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) dest[i] = part.owner(p.position.data() + D * i);
  exchange.migrate(p, dest);
  checkOwnership(p, whole, comm, domain, part);
  exchange.migrate(p, part.partition(p.position, weightsOf(p)));
  checkOwnership(p, whole, comm, domain, part);
  double load2 = 0;
  for (double x : weightsOf(p)) load2 += x;
  CHECK(loadImbalance(comm, load2) < 1.1);
}

// A whole checkpoint of n_moving fluid and n_fixed wall particles whose state segments hold
// `widths` values per particle, with two carried arrays laid out as the state; values from ids.
Checkpoint wholeCheckpoint(std::size_t n_moving, std::size_t n_fixed, const std::vector<std::size_t>& widths) {
  Checkpoint c;
  c.time = 0.25;
  c.step = 42;
  c.rhs_evals = 85;
  std::size_t width = 0;
  for (std::size_t w : widths) width += w;
  c.state.resize(n_moving * width);
  for (std::size_t k = 0; k < c.state.size(); ++k) c.state[k] = std::sin(0.37 * static_cast<double>(k)) + 0.001 * k;
  for (std::size_t i = 0; i < n_moving + n_fixed; ++i) c.id.push_back(i);
  for (const char* name : {"integrator.carried", "a.rate"}) {
    std::vector<double> v(c.state.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = std::cos(0.11 * static_cast<double>(k) + name[0]);
    c.arrays.emplace_back(name, v);
  }
  // Two values per particle in the frame's rows (a changing set's positions), and totals the
  // same on every process.
  std::vector<double> rows(2 * (n_moving + n_fixed));
  for (std::size_t k = 0; k < rows.size(); ++k) rows[k] = 0.5 * static_cast<double>(k) - 3.0;
  c.arrays.emplace_back("particles.position", rows);
  c.arrays.emplace_back("b.totals", std::vector<double>{3.0, 4.0, 5.0});
  return c;
}

// This process's part of the whole checkpoint: the rows [r n / P, (r+1) n / P) of the moving
// and of the fixed particles, the state segment-major over its moving rows (CheckpointRows).
Checkpoint checkpointPart(const Checkpoint& whole, std::size_t n_moving, std::size_t n_fixed,
                          const std::vector<std::size_t>& widths, const Communicator& comm, FrameRows& rows) {
  const auto r = static_cast<std::size_t>(comm.rank()), P = static_cast<std::size_t>(comm.size());
  const std::size_t m0 = r * n_moving / P, m1 = (r + 1) * n_moving / P;
  const std::size_t f0 = r * n_fixed / P, f1 = (r + 1) * n_fixed / P;
  rows = {m0, n_moving, f0, n_fixed};
  auto laidOut = [&](const std::vector<double>& all) {
    std::vector<double> part;
    std::size_t off = 0;
    for (std::size_t w : widths) {
      part.insert(part.end(), all.begin() + static_cast<std::ptrdiff_t>(off + m0 * w),
                  all.begin() + static_cast<std::ptrdiff_t>(off + m1 * w));
      off += n_moving * w;
    }
    return part;
  };
  Checkpoint part = whole;
  part.state = laidOut(whole.state);
  for (auto& [name, values] : part.arrays) {
    if (name == "b.totals") continue;  // the same on every process
    if (name == "particles.position") {  // the process's moving rows, then its fixed rows
      std::vector<double> mine(values.begin() + static_cast<std::ptrdiff_t>(2 * m0),
                               values.begin() + static_cast<std::ptrdiff_t>(2 * m1));
      mine.insert(mine.end(), values.begin() + static_cast<std::ptrdiff_t>(2 * (n_moving + f0)),
                  values.begin() + static_cast<std::ptrdiff_t>(2 * (n_moving + f1)));
      values = mine;
      continue;
    }
    values = laidOut(values);
  }
  part.id.assign(whole.id.begin() + static_cast<std::ptrdiff_t>(m0), whole.id.begin() + static_cast<std::ptrdiff_t>(m1));
  part.id.insert(part.id.end(), whole.id.begin() + static_cast<std::ptrdiff_t>(n_moving + f0),
                 whole.id.begin() + static_cast<std::ptrdiff_t>(n_moving + f1));
  return part;
}

}  // namespace

TEST_CASE("distributed output: the checkpoint written together is the whole one, its checksum computed in turn") {
  const Communicator comm = Communicator::world();
  const MPI_Comm handle = comm.handle();
  const std::vector<std::size_t> widths{2, 1, 2, 3};  // 2D: positions, density, velocities, a stress
  const std::size_t n_moving = 37, n_fixed = 11;      // divided unevenly by 2 and 4 processes
  const Checkpoint whole = wholeCheckpoint(n_moving, n_fixed, widths);
  FrameRows rows;
  const Checkpoint part = checkpointPart(whole, n_moving, n_fixed, widths, comm, rows);
  const CheckpointRows checkpoint_rows{rows, widths, {"integrator.carried", "a.rate"}, {{"particles.position", 2}}};
  CHECK(checkpointChecksum(part, checkpoint_rows, &handle) == checkpointChecksum(whole));

  // The frame and the checkpoint written by every process into one file read back as the whole.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("vesph_mpi_output_" + std::to_string(comm.size()));
  ParticleSet<2> share;
  for (std::uint64_t ident : part.id) {
    const double x = 0.01 * static_cast<double>(ident);
    share.add(Vec<2>(x, -x), Vec<2>(1.0, 2.0), kRho + x, 0.1, ident < n_moving ? ParticleKind::fluid : ParticleKind::wall,
              ident);
  }
  {
    OutputWriter<2> writer(dir.string(), "together", FileAttributes{2, "[scene]", kDx, 1.2 * kDx, "wendland_c2", {}, {}},
                           &handle);
    writer.writeFrame(0.25, 42, share, {DiagnosticsRow{0.25, 1e-3, 1.0, 2.0, 3.0, 0.01}}, &rows);
    writer.writeCheckpoint(part, &checkpoint_rows);
  }
  MPI_Barrier(handle);
  const ResumeSource back = readResumeSource(dir.string(), "together");
  CHECK(back.checkpoint.state == whole.state);
  CHECK(back.checkpoint.id == whole.id);
  REQUIRE(back.checkpoint.arrays.size() == whole.arrays.size());
  for (const auto& [name, values] : whole.arrays) {
    REQUIRE(back.checkpoint.find(name) != nullptr);
    CHECK(*back.checkpoint.find(name) == values);
  }
  CHECK(back.checkpoint.checksum == checkpointChecksum(whole));
  CHECK(back.frame_times == std::vector<double>{0.25});
  MPI_Barrier(handle);
  if (comm.rank() == 0) std::filesystem::remove_all(dir);
}

TEST_CASE("distributed 2D: migration, halo density sums and refresh match the serial set") {
  checkHaloDensities<2>({40, 24}, true, false);
}

TEST_CASE("distributed 2D periodic: the halo wraps across the periodic edge") {
  checkHaloDensities<2>({36, 20}, false, true);
}

TEST_CASE("distributed 3D: migration and halo density sums match the serial set") {
  checkHaloDensities<3>({14, 10, 8}, true, true);
}

// The ISPH pressure solve across processes (LinearSolver::solveAcross, src/isph/amg_solver.cpp):
// a non-symmetric 5-point operator on a 20 x 10 grid (a Laplacian with a convection term), its
// rows shared out unevenly (under 4 ranks the last holds none), each rank's matrix with its own
// rows first and the other ranks' unknowns it couples to as further columns, as the projection
// assembles it. The solution must be the serial one, on every rank, with the same report.
TEST_CASE("distributed pressure solve: hypre across ranks gives the serial solution, uneven and empty shares") {
  const Communicator comm = Communicator::world();
  const int P = comm.size(), r = comm.rank();
  constexpr int nx = 20, ny = 10, N = nx * ny;
  auto entries = [&](int row) {  // (column, value) of one global row
    std::vector<std::pair<int, double>> e;
    const int i = row % nx, j = row / nx;
    constexpr double c = 0.3;
    e.emplace_back(row, 4.0);
    if (i > 0) e.emplace_back(row - 1, -1.0 - c);
    if (i + 1 < nx) e.emplace_back(row + 1, -1.0 + c);
    if (j > 0) e.emplace_back(row - nx, -1.0);
    if (j + 1 < ny) e.emplace_back(row + nx, -1.0);
    return e;
  };
  auto rhs = [](int row) { return std::sin(0.37 * row) + 0.5; };
  // The serial solution, on every rank.
  SparseRowMatrix whole(N, N);
  std::vector<Eigen::Triplet<double>> t;
  for (int row = 0; row < N; ++row)
    for (auto [col, v] : entries(row)) t.emplace_back(row, col, v);
  whole.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd b_whole(N);
  for (int row = 0; row < N; ++row) b_whole[row] = rhs(row);
  const Eigen::SparseMatrix<double> whole_by_columns = whole;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(whole_by_columns);
  const Eigen::VectorXd serial = lu.solve(b_whole);
  // Uneven shares: weights 5, 3, 2, 0 (4 ranks), 5, 3 (2), the whole (1).
  const std::vector<int> weights = P == 4 ? std::vector<int>{5, 3, 2, 0} : P == 2 ? std::vector<int>{5, 3} : std::vector<int>(static_cast<std::size_t>(P), 1);
  int total = 0;
  for (int w : weights) total += w;
  std::vector<int> first(static_cast<std::size_t>(P) + 1, 0);
  for (int q = 0; q < P; ++q) first[static_cast<std::size_t>(q) + 1] = first[static_cast<std::size_t>(q)] + N * weights[static_cast<std::size_t>(q)] / total;
  first[static_cast<std::size_t>(P)] = N;
  const int lo = first[static_cast<std::size_t>(r)], hi = first[static_cast<std::size_t>(r) + 1], rows = hi - lo;
  DistributedRows layout;
  MPI_Comm handle = comm.handle();
  layout.communicator = &handle;
  layout.first_row = lo;
  layout.global_rows = N;
  for (int c = 0; c < rows; ++c) layout.column_global.push_back(lo + c);
  std::map<int, int> local_of;
  for (int c = 0; c < rows; ++c) local_of[lo + c] = c;
  std::vector<Eigen::Triplet<double>> mine;
  for (int row = lo; row < hi; ++row)
    for (auto [col, v] : entries(row)) {
      auto it = local_of.find(col);
      if (it == local_of.end()) {
        it = local_of.emplace(col, static_cast<int>(layout.column_global.size())).first;
        layout.column_global.push_back(col);
      }
      mine.emplace_back(row - lo, it->second, v);
    }
  SparseRowMatrix A(rows, static_cast<Eigen::Index>(layout.column_global.size()));
  A.setFromTriplets(mine.begin(), mine.end());
  Eigen::VectorXd b(rows), x = Eigen::VectorXd::Zero(rows);
  for (int row = lo; row < hi; ++row) b[row - lo] = rhs(row);
  LinearSolverOptions o;
  o.type = "bicgstab";
  o.preconditioner = "amg";
  o.tolerance = 1e-12;
  auto solver = makeLinearSolver(o);
  REQUIRE(solver->solvesAcrossProcesses());
  const SolveReport rep = solver->solveAcross(A, true, layout, b, x);
  CHECK(rep.ok);
  CHECK(rep.residual <= 1e-11);
  double err = 0;
  for (int row = lo; row < hi; ++row) err = std::max(err, std::abs(x[row - lo] - serial[row]));
  CHECK(comm.max(err) <= 1e-9 * serial.cwiseAbs().maxCoeff());
  // The same report everywhere (the iterations agreed).
  CHECK(comm.max(static_cast<double>(rep.iterations)) == static_cast<double>(rep.iterations));
  // Again with the kept pattern (values in place), a new right-hand side.
  b *= 2.0;
  const SolveReport again = solver->solveAcross(A, false, layout, b, x);
  CHECK(again.ok);
  err = 0;
  for (int row = lo; row < hi; ++row) err = std::max(err, std::abs(x[row - lo] - 2.0 * serial[row]));
  CHECK(comm.max(err) <= 2e-9 * serial.cwiseAbs().maxCoeff());
  // Nothing to solve anywhere: zeros, agreed.
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(rows), z = Eigen::VectorXd::Ones(rows);
  CHECK(solver->solveAcross(A, false, layout, zero, z).ok);
  CHECK((rows == 0 || z.cwiseAbs().maxCoeff() == 0.0));
  // A row without its own pressure on the first rank with rows (an equation 0 = b): every rank
  // reports the singular matrix.
  SparseRowMatrix S = A;
  if (rows > 0 && lo == 0)
    for (SparseRowMatrix::InnerIterator it(S, 0); it; ++it) it.valueRef() = 0.0;
  x.setZero();
  const SolveReport singular = solver->solveAcross(S, false, layout, b, x);
  CHECK_FALSE(singular.ok);
  CHECK(singular.message.find("singular") != std::string::npos);
}

}  // namespace vesph

int main(int argc, char** argv) {
  vesph::ensureMpiInitialised();
  doctest::Context context(argc, argv);
  // Only rank 0 prints the summary; every rank's failures are reported.
  if (vesph::Communicator::world().rank() != 0) context.setOption("minimal", true);
  const int failed = context.run();
  int any = failed != 0, all = 0;
  MPI_Allreduce(&any, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return all;
}
