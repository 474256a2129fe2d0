#include "vesph/parallel/particle_exchange.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace vesph {
namespace {

constexpr int kHaloCountTag = 7101, kHaloDataTag = 7102, kHaloIdTag = 7103, kRefreshTag = 7104;

void checkMpi(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

bool covers(Field::Range range, bool moving) {
  return range == Field::Range::all || (range == Field::Range::moving) == moving;
}

// Where particle i's values of a field over `range` lie (n_moving: the set's).
std::size_t fieldIndex(Field::Range range, std::size_t i, std::size_t n_moving) {
  return range == Field::Range::fixed ? i - n_moving : i;
}

// Doubles in one particle's record: position, velocity, density, mass, then the fields that
// cover it. Ids and kinds travel as a pair of 64-bit integers beside it.
template <int D>
std::size_t recordLength(const ParticleSet<D>& p, bool moving) {
  std::size_t n = 2 * D + 2;
  for (const auto& f : p.fields.all())
    if (covers(f->range, moving)) n += static_cast<std::size_t>(f->components);
  return n;
}

template <int D>
void packRecord(const ParticleSet<D>& p, std::size_t i, std::vector<double>& out, std::vector<std::uint64_t>& ids) {
  const bool moving = i < p.n_moving;
  for (int a = 0; a < D; ++a) out.push_back(p.position[D * i + a]);
  for (int a = 0; a < D; ++a) out.push_back(p.velocity[D * i + a]);
  out.push_back(p.density[i]);
  out.push_back(p.mass[i]);
  for (const auto& f : p.fields.all()) {
    if (!covers(f->range, moving)) continue;
    const double* v = f->at(fieldIndex(f->range, i, p.n_moving));
    out.insert(out.end(), v, v + f->components);
  }
  ids.push_back(p.id[i]);
  ids.push_back(p.kind[i]);
}

// A new particle set of nm moving and nf fixed particles, filled particle by particle from the
// old set or from records, then swapped in.
template <int D>
class SetBuilder {
 public:
  SetBuilder(const ParticleSet<D>& shape, std::size_t nm, std::size_t nf) : nm_(nm) {
    const std::size_t n = nm + nf;
    position_.resize(n * D);
    velocity_.resize(n * D);
    density_.resize(n);
    mass_.resize(n);
    kind_.resize(n);
    id_.resize(n);
    for (const auto& f : shape.fields.all()) {
      const std::size_t count = f->range == Field::Range::all ? n : f->range == Field::Range::moving ? nm : nf;
      fields_.emplace_back(count * static_cast<std::size_t>(f->components));
    }
  }

  void copy(const ParticleSet<D>& p, std::size_t i, std::size_t t) {
    for (int a = 0; a < D; ++a) {
      position_[D * t + a] = p.position[D * i + a];
      velocity_[D * t + a] = p.velocity[D * i + a];
    }
    density_[t] = p.density[i];
    mass_[t] = p.mass[i];
    kind_[t] = p.kind[i];
    id_[t] = p.id[i];
    const bool moving = i < p.n_moving;
    std::size_t k = 0;
    for (const auto& f : p.fields.all()) {
      std::vector<double>& out = fields_[k++];
      if (!covers(f->range, moving)) continue;
      const std::size_t c = static_cast<std::size_t>(f->components);
      std::copy_n(f->at(fieldIndex(f->range, i, p.n_moving)), c, out.begin() + static_cast<std::ptrdiff_t>(c * fieldIndex(f->range, t, nm_)));
    }
  }

  // Reads one record into particle t; returns the record's end.
  const double* read(const ParticleSet<D>& shape, const double* rec, const std::uint64_t* idk, std::size_t t) {
    const bool moving = t < nm_;
    for (int a = 0; a < D; ++a) position_[D * t + a] = *rec++;
    for (int a = 0; a < D; ++a) velocity_[D * t + a] = *rec++;
    density_[t] = *rec++;
    mass_[t] = *rec++;
    id_[t] = idk[0];
    kind_[t] = static_cast<std::uint8_t>(idk[1]);
    std::size_t k = 0;
    for (const auto& f : shape.fields.all()) {
      std::vector<double>& out = fields_[k++];
      if (!covers(f->range, moving)) continue;
      const std::size_t c = static_cast<std::size_t>(f->components);
      std::copy_n(rec, c, out.begin() + static_cast<std::ptrdiff_t>(c * fieldIndex(f->range, t, nm_)));
      rec += c;
    }
    return rec;
  }

  void install(ParticleSet<D>& p) {
    p.position.swap(position_);
    p.velocity.swap(velocity_);
    p.density.swap(density_);
    p.mass.swap(mass_);
    p.kind.swap(kind_);
    p.id.swap(id_);
    std::size_t k = 0;
    for (const auto& f : p.fields.all()) f->data.swap(fields_[k++]);
    p.n_moving = nm_;
    p.n_ghost_moving = p.n_ghost_fixed = 0;
  }

 private:
  std::size_t nm_;
  std::vector<double> position_, velocity_, density_, mass_;
  std::vector<std::uint8_t> kind_;
  std::vector<std::uint64_t> id_;
  std::vector<std::vector<double>> fields_;
};

int asCount(std::size_t n) {
  if (n > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::runtime_error("particle exchange: a message of more than 2^31 values (use more ranks)");
  return static_cast<int>(n);
}

}  // namespace

template <int D>
ParticleExchange<D>::ParticleExchange(const Communicator& comm, const Domain<D>& domain) : comm_(comm), domain_(domain) {}

template <int D>
std::size_t ParticleExchange<D>::migrate(ParticleSet<D>& p, std::span<const int> destination) {
  if (has_halo_ || p.n_ghost_moving + p.n_ghost_fixed != 0)
    throw std::logic_error("ParticleExchange::migrate with the halo in place (removeHalo first)");
  if (destination.size() != p.size()) throw std::invalid_argument("ParticleExchange::migrate: one destination per particle");
  const int ranks = comm_.size(), me = comm_.rank();
  const std::size_t R = static_cast<std::size_t>(ranks);
  // Per destination: its moving particles, then its fixed ones.
  std::vector<std::vector<std::size_t>> to(R);
  std::vector<std::uint64_t> counts(2 * R, 0);  // (moving, fixed) per destination
  for (std::size_t i = 0; i < p.size(); ++i) {
    const int d = destination[i];
    if (d < 0 || d >= ranks) throw std::invalid_argument("ParticleExchange::migrate: no such rank " + std::to_string(d));
    to[static_cast<std::size_t>(d)].push_back(i);  // moving particles come first in the set, so first here
    ++counts[2 * static_cast<std::size_t>(d) + (i < p.n_moving ? 0 : 1)];
  }
  std::vector<std::uint64_t> incoming(2 * R, 0);
  checkMpi(MPI_Alltoall(counts.data(), 2, MPI_UINT64_T, incoming.data(), 2, MPI_UINT64_T, comm_.handle()), "MPI_Alltoall");

  const std::size_t rec_m = recordLength(p, true), rec_f = recordLength(p, false);
  std::vector<double> send;
  std::vector<std::uint64_t> send_ids;
  std::vector<int> sc(R), sd(R), rc(R), rd(R), sci(R), sdi(R), rci(R), rdi(R);
  std::size_t sent_away = 0;
  for (std::size_t d = 0; d < R; ++d) {
    sd[d] = asCount(send.size());
    sdi[d] = asCount(send_ids.size());
    for (std::size_t i : to[d]) packRecord(p, i, send, send_ids);
    sc[d] = asCount(send.size()) - sd[d];
    sci[d] = asCount(send_ids.size()) - sdi[d];
    if (static_cast<int>(d) != me) sent_away += to[d].size();
  }
  std::size_t total = 0, total_ids = 0, new_moving = 0, new_fixed = 0;
  for (std::size_t s = 0; s < R; ++s) {
    const std::size_t m = incoming[2 * s], f = incoming[2 * s + 1];
    rd[s] = asCount(total);
    rdi[s] = asCount(total_ids);
    rc[s] = asCount(m * rec_m + f * rec_f);
    rci[s] = asCount(2 * (m + f));
    total += m * rec_m + f * rec_f;
    total_ids += 2 * (m + f);
    new_moving += m;
    new_fixed += f;
  }
  std::vector<double> recv(total);
  std::vector<std::uint64_t> recv_ids(total_ids);
  checkMpi(MPI_Alltoallv(send.data(), sc.data(), sd.data(), MPI_DOUBLE, recv.data(), rc.data(), rd.data(), MPI_DOUBLE,
                         comm_.handle()),
           "MPI_Alltoallv");
  checkMpi(MPI_Alltoallv(send_ids.data(), sci.data(), sdi.data(), MPI_UINT64_T, recv_ids.data(), rci.data(), rdi.data(),
                         MPI_UINT64_T, comm_.handle()),
           "MPI_Alltoallv");

  SetBuilder<D> out(p, new_moving, new_fixed);
  std::size_t tm = 0, tf = new_moving;
  for (std::size_t s = 0; s < R; ++s) {
    const double* rec = recv.data() + rd[s];
    const std::uint64_t* idk = recv_ids.data() + rdi[s];
    for (std::uint64_t k = 0; k < incoming[2 * s]; ++k, idk += 2) rec = out.read(p, rec, idk, tm++);
    for (std::uint64_t k = 0; k < incoming[2 * s + 1]; ++k, idk += 2) rec = out.read(p, rec, idk, tf++);
  }
  out.install(p);
  counters_.particles_migrated += sent_away;
  return sent_away;
}

template <int D>
void ParticleExchange<D>::buildHalo(ParticleSet<D>& p, const std::vector<Box<D>>& boxes, double radius) {
  if (has_halo_) throw std::logic_error("ParticleExchange::buildHalo: the halo is already in place");
  if (boxes.size() != static_cast<std::size_t>(comm_.size()))
    throw std::invalid_argument("ParticleExchange::buildHalo: one box per rank");
  if (!(radius > 0)) throw std::invalid_argument("ParticleExchange::buildHalo: radius must be positive");
  const int me = comm_.rank();
  const Box<D>& mine = boxes[static_cast<std::size_t>(me)];
  neighbours_.clear();
  for (int r = 0; r < comm_.size(); ++r)
    if (r != me && distanceBetweenBoxes(domain_, mine, boxes[static_cast<std::size_t>(r)]) < radius) neighbours_.push_back(r);
  const std::size_t K = neighbours_.size();

  // What each neighbour needs: this rank's particles within the radius of its box.
  send_.assign(K, {});
  send_moving_.assign(K, 0);
  for (std::size_t k = 0; k < K; ++k) {
    const Box<D>& theirs = boxes[static_cast<std::size_t>(neighbours_[k])];
    for (std::size_t i = 0; i < p.size(); ++i)
      if (distanceToBox(domain_, p.position.data() + D * i, theirs) < radius) {
        send_[k].push_back(static_cast<Index>(i));
        if (i < p.n_moving) ++send_moving_[k];
      }
  }
  // Counts, then the records.
  std::vector<std::uint64_t> counts_out(2 * K), counts_in(2 * K);
  std::vector<MPI_Request> requests;
  requests.reserve(4 * K);
  for (std::size_t k = 0; k < K; ++k) {
    counts_out[2 * k] = send_moving_[k];
    counts_out[2 * k + 1] = send_[k].size() - send_moving_[k];
    requests.emplace_back();
    checkMpi(MPI_Irecv(&counts_in[2 * k], 2, MPI_UINT64_T, neighbours_[k], kHaloCountTag, comm_.handle(), &requests.back()), "MPI_Irecv");
  }
  for (std::size_t k = 0; k < K; ++k) {
    requests.emplace_back();
    checkMpi(MPI_Isend(&counts_out[2 * k], 2, MPI_UINT64_T, neighbours_[k], kHaloCountTag, comm_.handle(), &requests.back()), "MPI_Isend");
  }
  checkMpi(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  requests.clear();

  const std::size_t rec_m = recordLength(p, true), rec_f = recordLength(p, false);
  std::vector<std::vector<double>> out(K), in(K);
  std::vector<std::vector<std::uint64_t>> out_ids(K), in_ids(K);
  recv_moving_.assign(K, 0);
  recv_fixed_.assign(K, 0);
  for (std::size_t k = 0; k < K; ++k) {
    recv_moving_[k] = counts_in[2 * k];
    recv_fixed_[k] = counts_in[2 * k + 1];
    in[k].resize(recv_moving_[k] * rec_m + recv_fixed_[k] * rec_f);
    in_ids[k].resize(2 * (recv_moving_[k] + recv_fixed_[k]));
    requests.emplace_back();
    checkMpi(MPI_Irecv(in[k].data(), asCount(in[k].size()), MPI_DOUBLE, neighbours_[k], kHaloDataTag, comm_.handle(), &requests.back()), "MPI_Irecv");
    requests.emplace_back();
    checkMpi(MPI_Irecv(in_ids[k].data(), asCount(in_ids[k].size()), MPI_UINT64_T, neighbours_[k], kHaloIdTag, comm_.handle(), &requests.back()), "MPI_Irecv");
  }
  for (std::size_t k = 0; k < K; ++k) {
    for (Index i : send_[k]) packRecord(p, i, out[k], out_ids[k]);
    requests.emplace_back();
    checkMpi(MPI_Isend(out[k].data(), asCount(out[k].size()), MPI_DOUBLE, neighbours_[k], kHaloDataTag, comm_.handle(), &requests.back()), "MPI_Isend");
    requests.emplace_back();
    checkMpi(MPI_Isend(out_ids[k].data(), asCount(out_ids[k].size()), MPI_UINT64_T, neighbours_[k], kHaloIdTag, comm_.handle(), &requests.back()), "MPI_Isend");
  }
  checkMpi(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");

  layout_.owned_moving = p.n_moving;
  layout_.owned_fixed = p.nFixed();
  layout_.ghost_moving = std::accumulate(recv_moving_.begin(), recv_moving_.end(), std::size_t{0});
  layout_.ghost_fixed = std::accumulate(recv_fixed_.begin(), recv_fixed_.end(), std::size_t{0});
  recv_moving_at_.assign(K, 0);
  recv_fixed_at_.assign(K, 0);
  for (std::size_t k = 1; k < K; ++k) {
    recv_moving_at_[k] = recv_moving_at_[k - 1] + recv_moving_[k - 1];
    recv_fixed_at_[k] = recv_fixed_at_[k - 1] + recv_fixed_[k - 1];
  }
  const std::size_t nm = layout_.owned_moving + layout_.ghost_moving;
  const std::size_t nf = layout_.owned_fixed + layout_.ghost_fixed;
  SetBuilder<D> set(p, nm, nf);
  for (std::size_t i = 0; i < layout_.owned_moving; ++i) set.copy(p, i, i);
  for (std::size_t f = 0; f < layout_.owned_fixed; ++f) set.copy(p, layout_.owned_moving + f, nm + f);
  for (std::size_t k = 0; k < K; ++k) {
    const double* rec = in[k].data();
    const std::uint64_t* idk = in_ids[k].data();
    for (std::size_t j = 0; j < recv_moving_[k]; ++j, idk += 2)
      rec = set.read(p, rec, idk, layout_.owned_moving + recv_moving_at_[k] + j);
    for (std::size_t j = 0; j < recv_fixed_[k]; ++j, idk += 2)
      rec = set.read(p, rec, idk, nm + layout_.owned_fixed + recv_fixed_at_[k] + j);
  }
  set.install(p);
  p.n_ghost_moving = layout_.ghost_moving;
  p.n_ghost_fixed = layout_.ghost_fixed;
  // This rank's fixed particles moved up past the ghost moving ones.
  for (std::size_t k = 0; k < K; ++k)
    for (std::size_t s = send_moving_[k]; s < send_[k].size(); ++s) send_[k][s] += static_cast<Index>(layout_.ghost_moving);
  n_moving_with_halo_ = nm;
  has_halo_ = true;
  counters_.neighbour_ranks = K;
  counters_.ghosts_received = layout_.ghosts();
  counters_.ghosts_sent = 0;
  for (const auto& s : send_) counters_.ghosts_sent += s.size();
  send_buffer_.resize(K);
  recv_buffer_.resize(K);
}

template <int D>
void ParticleExchange<D>::keepOnly(ParticleSet<D>& p, std::span<const char> keep) {
  if (has_halo_) throw std::logic_error("ParticleExchange::keepOnly with the halo in place");
  if (keep.size() != p.size()) throw std::invalid_argument("ParticleExchange::keepOnly: one flag per particle");
  std::size_t nm = 0, nf = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (keep[i]) ++(i < p.n_moving ? nm : nf);
  SetBuilder<D> set(p, nm, nf);
  std::size_t tm = 0, tf = nm;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (keep[i]) set.copy(p, i, i < p.n_moving ? tm++ : tf++);
  set.install(p);
}

template <int D>
void ParticleExchange<D>::reorder(ParticleSet<D>& p, std::span<const std::size_t> order) {
  if (order.size() != p.size()) throw std::invalid_argument("ParticleExchange::reorder: one place per particle");
  SetBuilder<D> set(p, p.n_moving, p.nFixed());
  for (std::size_t t = 0; t < order.size(); ++t) {
    if ((order[t] < p.n_moving) != (t < p.n_moving))
      throw std::invalid_argument("ParticleExchange::reorder: moving and fixed particles must keep their places");
    set.copy(p, order[t], t);
  }
  const std::size_t gm = p.n_ghost_moving, gf = p.n_ghost_fixed;
  set.install(p);
  p.n_ghost_moving = gm;
  p.n_ghost_fixed = gf;
}

template <int D>
void ParticleExchange<D>::removeHalo(ParticleSet<D>& p) {
  if (!has_halo_) return;
  const std::size_t om = layout_.owned_moving, of = layout_.owned_fixed;
  SetBuilder<D> set(p, om, of);
  for (std::size_t i = 0; i < om; ++i) set.copy(p, i, i);
  for (std::size_t f = 0; f < of; ++f) set.copy(p, p.n_moving + f, om + f);
  set.install(p);
  has_halo_ = false;
  layout_.ghost_moving = layout_.ghost_fixed = 0;
}

template <int D>
void ParticleExchange<D>::refresh(std::span<const HaloArray> arrays) {
  if (!has_halo_) throw std::logic_error("ParticleExchange::refresh without a halo");
  const std::size_t K = neighbours_.size(), nmh = n_moving_with_halo_;
  auto valuesFor = [&](std::size_t moving, std::size_t fixed) {
    std::size_t n = 0;
    for (const HaloArray& a : arrays) {
      const std::size_t c = static_cast<std::size_t>(a.components);
      n += c * ((a.range != Field::Range::fixed ? moving : 0) + (a.range != Field::Range::moving ? fixed : 0));
    }
    return n;
  };
  std::vector<MPI_Request>& requests = requests_;
  requests.resize(2 * K);  // sized at the first refresh after a halo build
  for (std::size_t k = 0; k < K; ++k) {
    const std::size_t n = valuesFor(recv_moving_[k], recv_fixed_[k]);
    if (recv_buffer_[k].size() < n) recv_buffer_[k].resize(n);
    checkMpi(MPI_Irecv(recv_buffer_[k].data(), asCount(n), MPI_DOUBLE, neighbours_[k], kRefreshTag, comm_.handle(), &requests[k]), "MPI_Irecv");
  }
  for (std::size_t k = 0; k < K; ++k) {
    const std::size_t n = valuesFor(send_moving_[k], send_[k].size() - send_moving_[k]);
    if (send_buffer_[k].size() < n) send_buffer_[k].resize(n);
    double* out = send_buffer_[k].data();
    for (const HaloArray& a : arrays) {
      const std::size_t c = static_cast<std::size_t>(a.components);
      const std::size_t s0 = a.range == Field::Range::fixed ? send_moving_[k] : 0;
      const std::size_t s1 = a.range == Field::Range::moving ? send_moving_[k] : send_[k].size();
      for (std::size_t s = s0; s < s1; ++s) {
        const double* v = a.data + c * fieldIndex(a.range, send_[k][s], nmh);
        for (std::size_t q = 0; q < c; ++q) *out++ = v[q];
      }
    }
    checkMpi(MPI_Isend(send_buffer_[k].data(), asCount(n), MPI_DOUBLE, neighbours_[k], kRefreshTag, comm_.handle(), &requests[K + k]), "MPI_Isend");
    counters_.bytes_sent += n * sizeof(double);
  }
  checkMpi(MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
  for (std::size_t k = 0; k < K; ++k) {
    const double* in = recv_buffer_[k].data();
    const std::size_t m0 = layout_.owned_moving + recv_moving_at_[k];
    const std::size_t f0 = nmh + layout_.owned_fixed + recv_fixed_at_[k];
    for (const HaloArray& a : arrays) {
      const std::size_t c = static_cast<std::size_t>(a.components);
      if (a.range != Field::Range::fixed)
        for (std::size_t j = 0; j < recv_moving_[k]; ++j, in += c) std::copy_n(in, c, a.data + c * (m0 + j));
      if (a.range != Field::Range::moving)
        for (std::size_t j = 0; j < recv_fixed_[k]; ++j, in += c) std::copy_n(in, c, a.data + c * fieldIndex(a.range, f0 + j, nmh));
    }
  }
  ++counters_.refreshes;
  counters_.messages_sent += K;
}

template <int D>
std::vector<HaloArray> ParticleExchange<D>::everyArray(ParticleSet<D>& p) {
  std::vector<HaloArray> arrays{{p.position.data(), D, Field::Range::all},
                                {p.velocity.data(), D, Field::Range::all},
                                {p.density.data(), 1, Field::Range::all}};
  for (const auto& f : p.fields.all()) arrays.push_back({f->data.data(), f->components, f->range});
  return arrays;
}

template class ParticleExchange<2>;
template class ParticleExchange<3>;

}  // namespace vesph
