#include "vesph/boundary/inflow_outflow.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <tuple>

#include "vesph/boundary/registry.hpp"


namespace vesph {

template <int D>
std::unique_ptr<InflowOutflow<D>> InflowOutflow<D>::fromConfig(ConfigTable& root, ParticleSet<D>& p,
                                                               const Domain<D>& dom, double dx, double rho0,
                                                               double support, std::uint64_t& next_id) {
  const bool inflow = root.isTable("inflow"), outflow = root.isTable("outflow");
  if (!inflow && !outflow) return nullptr;
  auto hook = std::make_unique<InflowOutflow<D>>();
  if (inflow) {
    ConfigTable in = root.table("inflow", false);
    const Vec<D> lo = in.vector<D>("min", std::nullopt, "m");
    const Vec<D> hi = in.vector<D>("max", std::nullopt, "m");
    std::tie(hook->axis_, hook->sign_) = in.coordinateAxis<D>("direction", "a coordinate unit vector, e.g. [1.0, 0.0] for +x");
    std::array<long, D> n;
    for (int a = 0; a < D; ++a) {
      const double cells = (hi[a] - lo[a]) / dx;
      if (!(cells > 0.5) || std::abs(cells - std::round(cells)) > 1e-6 * std::max(1.0, cells)) {
        std::ostringstream os;
        os << "a corner above min by a whole number of particle spacings (" << dx << " m) along axis " << a;
        in.fail("max", os.str());
      }
      if (lo[a] < dom.lo[a] - 1e-9 * dom.length(a) || hi[a] > dom.hi[a] + 1e-9 * dom.length(a))
        in.fail("max", "a buffer inside the domain [domain.min, domain.max]");
      n[a] = std::lround(cells);
    }
    const int ax = hook->axis_;
    hook->depth_ = hi[ax] - lo[ax];
    hook->inlet_ = hook->sign_ > 0 ? hi[ax] : lo[ax];
    if (hook->depth_ < support * (1 - 1e-9)) {
      std::ostringstream os;
      os << "a buffer at least one kernel support deep along the flow (" << support << " m = "
         << std::ceil(support / dx - 1e-9) << " spacings), so that fluid at the inlet has a full support; it is "
         << hook->depth_ << " m";
      in.fail("max", os.str());
    }
    hook->spacing_ = dx;
    hook->lo_ = lo;
    hook->counts_ = n;
    hook->extrapolated_ = in.choice("velocity", "prescribed", {"prescribed", "extrapolated"}) == "extrapolated";
    if (hook->extrapolated_) {
      for (const char* key : {"profile", "mean_velocity", "ramp_time", "profile_axis"})
        if (in.has(key))
          in.fail(key, std::string("no ") + key + " with velocity = \"extrapolated\" (the buffer follows the fluid at the inlet; "
                       "the scene drives the flow, e.g. by a body force in the die)");
      hook->profile_ = "extrapolated";
    }
    if (!hook->extrapolated_) {
      hook->profile_ = in.choice("profile", "parabolic", {"uniform", "parabolic"});
      hook->mean_velocity_ = in.number("mean_velocity", std::nullopt, Bound::positive, "m/s");
      hook->ramp_time_ = in.number("ramp_time", 0.0, Bound::nonnegative, "s");
    }
    if (in.has("radius")) {
      if (D == 2) in.fail("radius", "only in 3D (a circular nozzle's cross-section; in 2D the buffer box is the nozzle)");
      if (hook->extrapolated_)
        in.fail("radius", "only with velocity = \"prescribed\" (the extrapolated buffer follows the fluid lane by lane "
                          "on the lattice of a box)");
      if (in.has("profile_axis")) in.fail("profile_axis", "absent with radius (the nozzle's profile is radial)");
      hook->nozzle_radius_ = in.number("radius", std::nullopt, Bound::positive, "m");
      if (hook->nozzle_radius_ < dx * (1 - 1e-9)) in.fail("radius", "at least one particle spacing");
      for (int a = 0; a < D; ++a)
        if (a != ax && hi[a] - lo[a] < 2 * hook->nozzle_radius_ * (1 - 1e-9)) {
          std::ostringstream os;
          os << "a circle of diameter " << 2 * hook->nozzle_radius_ << " m inside the buffer box's cross-section, which is "
             << hi[a] - lo[a] << " m wide along axis " << a;
          in.fail("radius", os.str());
        }
      hook->placeNozzle(p, lo, hi, n, dx, rho0, next_id);
    } else {
      hook->placeBox(p, in, lo, hi, n, dx, rho0, next_id);
    }
  }
  if (outflow) {
    ConfigTable out = root.table("outflow", false);
    hook->outflow_ = true;
    std::tie(hook->out_axis_, hook->out_sign_) = out.coordinateAxis<D>("normal", "a coordinate unit vector, e.g. [1.0, 0.0] for +x");
    hook->out_position_ = out.number("position", std::nullopt, Bound::any, "m");
    const int a = hook->out_axis_;
    const double edge = hook->out_sign_ > 0 ? dom.hi[a] : dom.lo[a];
    if ((edge - hook->out_position_) * hook->out_sign_ < support * (1 - 1e-9)) {
      std::ostringstream os;
      os << "an outflow plane inside the domain by at least one kernel support (" << support
         << " m) from its boundary at " << edge << " m, so that particles are removed before they leave it";
      out.fail("position", os.str());
    }
  }
  if (hook->extrapolated_) {
    std::size_t lanes = 1;
    for (int a = 0; a < D; ++a)
      if (a != hook->axis_) lanes *= static_cast<std::size_t>(hook->counts_[a]);
    hook->lane_speed_.assign(lanes, 0.0);
    hook->lane_sum_.assign(lanes, 0.0);
    hook->lane_count_.assign(lanes, 0);
    hook->lane_trail_.assign(lanes, 0.0);
    hook->lane_lead_.assign(lanes, 0.0);
    hook->lane_shift_.assign(lanes, 0.0);
    hook->support_ = support;
  }
  hook->fluid_count_ = p.n_moving;
  return hook;
}

template <int D>
void InflowOutflow<D>::placeBox(ParticleSet<D>& p, ConfigTable& in, const Vec<D>& lo, const Vec<D>& hi,
                                const std::array<long, D>& n, double dx, double rho0, std::uint64_t& next_id) {
  // The buffer particles: cell centres of the box, as for blocks (fixed, kind inflow).
  const int ax = axis_;
  int across = D == 2 ? 1 - ax : -1;
  double width = 0;  // of the parabolic profile
  if (profile_ == "parabolic") {
    if (D == 3 || in.has("profile_axis"))
      across = static_cast<int>(in.integer("profile_axis", D == 2 ? std::optional<long long>(1 - ax) : std::nullopt, 0, D - 1));
    if (across == ax) in.fail("profile_axis", "an axis across the flow direction (not the flow axis)");
    width = hi[across] - lo[across];
  }
  long total = 1;
  for (int a = 0; a < D; ++a) total *= n[a];
  const double mass = rho0 * std::pow(dx, D);
  for (long k = 0; k < total; ++k) {
    long rem = k;
    Vec<D> x;
    for (int a = 0; a < D; ++a) {
      x[a] = lo[a] + (static_cast<double>(rem % n[a]) + 0.5) * dx;
      rem /= n[a];
    }
    double u = extrapolated_ ? 0.0 : mean_velocity_;
    if (profile_ == "parabolic") {
      const double eta = (x[across] - lo[across]) / width;
      u = 6.0 * mean_velocity_ * eta * (1.0 - eta);
    }
    addBufferParticle(p, x, u, rho0, mass, next_id);
  }
}

template <int D>
void InflowOutflow<D>::addBufferParticle(ParticleSet<D>& p, const Vec<D>& x, double speed, double rho0, double mass,
                                         std::uint64_t& next_id) {
  Vec<D> v = Vec<D>::Zero();
  v[axis_] = sign_ * speed * rampFactor(0.0);
  buffer_.push_back(p.nFixed());
  speed_.push_back(speed);
  lane_.push_back(laneOf(x));
  p.add(x, v, rho0, mass, ParticleKind::inflow, next_id++);
}

template <int D>
void InflowOutflow<D>::placeNozzle(ParticleSet<D>& p, const Vec<D>& lo, const Vec<D>& hi, const std::array<long, D>& n,
                                   double dx, double rho0, std::uint64_t& next_id) {
  // Rings about the axis through the cross-section's centre, in the order and orientation of a
  // `cylinder` block along +e_axis (src/sim/particle_generation.cpp, placeRings), so that a
  // fluid cylinder downstream continues the buffer's rings: transverse unit vectors u = e_y for
  // a flow along x, else e_x, and v = e x u; every other ring turned by half a step.
  const int ax = axis_;
  const double pi = std::numbers::pi, R = nozzle_radius_;
  Vec<D> e = Vec<D>::Zero(), u = Vec<D>::Zero(), v = Vec<D>::Zero(), centre = 0.5 * (lo + hi);
  e[ax] = 1;
  if constexpr (D == 3) {
    u[ax == 0 ? 1 : 0] = 1;
    v = Vec<D>(e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0]);
  }
  const long n_r = std::max(1L, std::lround(R / dx));
  const double dr = R / static_cast<double>(n_r);
  for (long j = 0; j < n[ax]; ++j) {
    Vec<D> station = centre;
    station[ax] = lo[ax] + (static_cast<double>(j) + 0.5) * dx;
    for (long k = 0; k < n_r; ++k) {
      const double r = (static_cast<double>(k) + 0.5) * dr;
      const long count = std::max(1L, std::lround(2 * pi * r / dx));
      const double step = 2 * pi / static_cast<double>(count), phase = (k % 2) * 0.5 * step;
      const double mass = rho0 * 2 * pi * r * dr * dx / static_cast<double>(count);
      // The ring carries its annulus' area-weighted mean speed, 2U (1 - (r_in^2 + r_out^2) / 2R^2)
      // for the parabola, so that the rings' flow rate sum_k m_k u_k / dx is exactly U pi R^2 (the
      // ring midpoint's speed would be short by dr^2 / 2R^2 of it).
      const double r_in = r - 0.5 * dr, r_out = r + 0.5 * dr;
      const double speed = profile_ == "parabolic"
                               ? 2.0 * mean_velocity_ * (1.0 - (r_in * r_in + r_out * r_out) / (2 * R * R))
                               : mean_velocity_;
      for (long i = 0; i < count; ++i) {
        const double theta = phase + step * static_cast<double>(i);
        addBufferParticle(p, Vec<D>(station + r * (std::cos(theta) * u + std::sin(theta) * v)), speed, rho0, mass,
                          next_id);
      }
    }
  }
}

template <int D>
long InflowOutflow<D>::laneOf(const Vec<D>& x) const {
  // The buffer's lattice coordinates across the flow, as one index; -1 outside the buffer's
  // cross-section.
  long lane = 0, stride = 1;
  for (int a = 0; a < D; ++a) {
    if (a == axis_) continue;
    const long c = static_cast<long>(std::floor((x[a] - lo_[a]) / spacing_));
    if (c < 0 || c >= counts_[a]) return -1;
    lane += stride * c;
    stride *= counts_[a];
  }
  return lane;
}

template <int D>
void InflowOutflow<D>::followFluid(ParticleSet<D>& p, const double* y, std::size_t n) {
  // Per lane: the mean velocity along the flow of the fluid within two spacings downstream of
  // the inlet (the buffer's velocity as the fluid sees it), and the most upstream fluid
  // particle within one support. The lane then moves so that its leading buffer particle sits
  // one spacing behind that fluid particle: the buffer stays attached to the fluid, so the
  // inlet never opens a gap, and never moves backwards.
  std::fill(lane_sum_.begin(), lane_sum_.end(), 0.0);
  std::fill(lane_count_.begin(), lane_count_.end(), 0);
  std::fill(lane_trail_.begin(), lane_trail_.end(), std::numeric_limits<double>::infinity());
  std::fill(lane_lead_.begin(), lane_lead_.end(), -std::numeric_limits<double>::infinity());
  const double* v = y + n * (D + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = (y[D * i + axis_] - inlet_) * sign_;
    if (s >= support_) continue;
    const long lane = laneOf(Eigen::Map<const Vec<D>>(y + D * i));
    if (lane < 0) continue;
    const std::size_t l = static_cast<std::size_t>(lane);
    lane_trail_[l] = std::min(lane_trail_[l], s);
    if (s >= 0 && s < 2 * spacing_) {
      lane_sum_[l] += sign_ * v[D * i + axis_];
      ++lane_count_[l];
    }
  }
  const std::size_t n0 = p.n_moving;
  for (std::size_t k = 0; k < buffer_.size(); ++k) {
    const std::size_t l = static_cast<std::size_t>(lane_[k]);
    lane_lead_[l] = std::max(lane_lead_[l], (p.position[D * (n0 + buffer_[k]) + axis_] - inlet_) * sign_);
  }
  if (ParticleDistribution<D>* dist = this->distribution()) {
    // A lane's fluid and buffer particles may lie on several processes: its sums, its most
    // upstream fluid particle and its leading buffer particle over all of them.
    const std::size_t lanes = lane_sum_.size();
    std::vector<double> sums(2 * lanes), extremes(2 * lanes);
    for (std::size_t l = 0; l < lanes; ++l) {
      sums[l] = lane_sum_[l];
      sums[lanes + l] = static_cast<double>(lane_count_[l]);
      extremes[l] = -lane_trail_[l];
      extremes[lanes + l] = lane_lead_[l];
    }
    dist->sum(sums);
    dist->max(extremes);
    for (std::size_t l = 0; l < lanes; ++l) {
      lane_sum_[l] = sums[l];
      lane_count_[l] = static_cast<long>(sums[lanes + l]);
      lane_trail_[l] = -extremes[l];
      lane_lead_[l] = extremes[lanes + l];
    }
  }
  for (std::size_t l = 0; l < lane_speed_.size(); ++l) {
    if (lane_count_[l] > 0) lane_speed_[l] = std::max(0.0, lane_sum_[l] / static_cast<double>(lane_count_[l]));
    lane_shift_[l] = std::isfinite(lane_trail_[l]) ? std::max(0.0, lane_trail_[l] - spacing_ - lane_lead_[l]) : 0.0;
  }
}

template <int D>
double InflowOutflow<D>::rampFactor(double t) const {
  if (ramp_time_ <= 0 || t >= ramp_time_) return 1.0;
  return 0.5 * (1.0 - std::cos(std::numbers::pi * t / ramp_time_));
}

template <int D>
double InflowOutflow<D>::rampIntegral(double t) const {
  if (ramp_time_ <= 0) return t;
  const double T = ramp_time_;
  if (t >= T) return 0.5 * T + (t - T);
  return 0.5 * t - 0.5 * T / std::numbers::pi * std::sin(std::numbers::pi * t / T);
}

template <int D>
void InflowOutflow<D>::distributing(ParticleSet<D>& whole) {
  Field& speed = whole.fields.require("inflow_speed", 1, Field::Range::fixed);
  speed.refreshed_in_halo = false;  // the owner moves its buffer particles; ghosts follow their positions
  speed.data.assign(whole.nFixed(), 0.0);
  for (std::size_t k = 0; k < buffer_.size(); ++k) speed.at(buffer_[k])[0] = speed_[k];
}

template <int D>
void InflowOutflow<D>::redistributed(StepContext<D>& system) {
  const ParticleSet<D>& p = system.particles;
  const Field* speed = p.fields.find("inflow_speed");
  if (!speed) throw std::logic_error("InflowOutflow::redistributed before distributing");
  buffer_.clear();
  speed_.clear();
  lane_.clear();
  for (std::size_t k = 0; k < p.ownedEnd() - p.n_moving; ++k)
    if (p.kind[p.n_moving + k] == static_cast<std::uint8_t>(ParticleKind::inflow)) {
      buffer_.push_back(k);
      speed_.push_back(speed->at(k)[0]);
      // A buffer particle moves along the flow only: its lane is that of its position.
      lane_.push_back(laneOf(Eigen::Map<const Vec<D>>(p.position.data() + D * (p.n_moving + k))));
    }
  fluid_count_ = p.ownedMoving();
}

template <int D>
void InflowOutflow<D>::apply(StepContext<D>& system, double t, double dt, double* y) {
  ParticleSet<D>& p = system.particles;
  const std::size_t n0 = p.n_moving;  // the fixed particles' start (a process's ghosts before it)
  const std::size_t owned = p.ownedMoving();  // the state's particles
  release_.clear();
  released_offsets_.clear();
  remove_.clear();
  // Across processes, every process takes part in the lanes' reductions (followFluid), also
  // one that holds no buffer particle.
  if (!buffer_.empty() || (extrapolated_ && this->distribution())) {
    // A prescribed buffer moves by the exact integral of its (ramped) speed over the step; an
    // extrapolated one follows the fluid (followFluid).
    const double advance = rampIntegral(t) - rampIntegral(t - dt);
    const double factor = rampFactor(t);
    if (extrapolated_) followFluid(p, y, owned);
    for (std::size_t k = 0; k < buffer_.size(); ++k) {
      const std::size_t b = n0 + buffer_[k];
      double& x = p.position[D * b + axis_];
      if (extrapolated_) {
        const std::size_t l = static_cast<std::size_t>(lane_[k]);
        x += sign_ * lane_shift_[l];
        p.velocity[D * b + axis_] = sign_ * lane_speed_[l];
      } else {
        x += sign_ * speed_[k] * advance;
        p.velocity[D * b + axis_] = sign_ * speed_[k] * factor;
      }
      if ((x - inlet_) * sign_ > 0) {
        release_.push_back(static_cast<Index>(b));
        released_offsets_.push_back(buffer_[k]);
      }
    }
  }
  if (outflow_)
    for (std::size_t i = 0; i < owned; ++i)
      if ((y[D * i + out_axis_] - out_position_) * out_sign_ > 0) remove_.push_back(static_cast<Index>(i));
  fluid_count_ = owned + release_.size() - remove_.size();
}

template <int D>
void InflowOutflow<D>::collectChanges(const StepContext<D>&, ParticleChanges& out) {
  out.remove.insert(out.remove.end(), remove_.begin(), remove_.end());
  out.release.insert(out.release.end(), release_.begin(), release_.end());
}

template <int D>
void InflowOutflow<D>::resized(StepContext<D>& system, const ParticleRemap& remap) {
  // A released buffer particle goes back by the buffer depth: its lane keeps its spacing.
  ParticleSet<D>& p = system.particles;
  for (std::size_t off : released_offsets_) p.position[D * (remap.newMoving() + off) + axis_] -= sign_ * depth_;
  released_ += release_.size();
  removed_ += remove_.size();
  release_.clear();
  released_offsets_.clear();
  remove_.clear();
  fluid_count_ = p.ownedMoving();
}

template <int D>
void InflowOutflow<D>::saveCarried(NamedArrays& out) const {
  // A run across processes: the whole run's totals (collective), which process 0 takes back.
  std::vector<double> totals{static_cast<double>(released_), static_cast<double>(removed_)};
  if (this->distribution()) this->distribution()->sum(totals);
  out.emplace_back("totals", totals);
  if (!lane_speed_.empty()) out.emplace_back("lane_speed", lane_speed_);
}

template <int D>
void InflowOutflow<D>::restoreCarried(const ArrayLookup& find) {
  const std::vector<double>* totals = find("totals");
  if (!totals || totals->size() != 2) throw InputError("--resume: the checkpoint lacks the inflow/outflow totals");
  const bool mine = !this->distribution() || this->distribution()->rank() == 0;  // the totals are counted once
  released_ = mine ? static_cast<std::uint64_t>((*totals)[0]) : 0;
  removed_ = mine ? static_cast<std::uint64_t>((*totals)[1]) : 0;
  if (!lane_speed_.empty()) {
    const std::vector<double>* speeds = find("lane_speed");
    if (!speeds || speeds->size() != lane_speed_.size()) throw InputError("--resume: the checkpoint lacks the inflow lanes' speeds");
    lane_speed_ = *speeds;
  }
}

template <int D>
void InflowOutflow<D>::diagnostics(std::vector<double>& values) const {
  // The row of a step counts that step's changes (made right after it); a run across
  // processes, every process's.
  double row[3] = {static_cast<double>(released_ + release_.size()), static_cast<double>(removed_ + remove_.size()),
                   static_cast<double>(fluid_count_)};
  if (this->distribution()) this->distribution()->sum(row);
  values.insert(values.end(), std::begin(row), std::end(row));
}

template <int D>
void InflowOutflow<D>::summarize(nlohmann::json& summary) const {
  nlohmann::json j;
  // A run across processes: every process's counts.
  auto total = [&](std::uint64_t local) { return this->distribution() ? this->distribution()->sum(local) : local; };
  j["released"] = total(released_);
  j["removed"] = total(removed_);
  j["fluid_particles"] = total(fluid_count_);
  const std::uint64_t buffer_particles = total(buffer_.size());
  if (buffer_particles > 0) {
    j["buffer_particles"] = buffer_particles;
    j["velocity"] = extrapolated_ ? "extrapolated" : "prescribed";
    if (!extrapolated_) {
      j["mean_velocity"] = mean_velocity_;
      j["profile"] = profile_;
      if (nozzle_radius_ > 0) j["nozzle_radius"] = nozzle_radius_;
    } else {
      double mean = 0;
      for (double u : lane_speed_) mean += u;
      j["inlet_mean_velocity"] = lane_speed_.empty() ? 0.0 : mean / static_cast<double>(lane_speed_.size());
    }
  }
  summary["flow"] = j;
}

template <int D>
std::string InflowOutflow<D>::describe() const {
  std::ostringstream os;
  const char* axes = "xyz";
  if (!buffer_.empty() && extrapolated_)
    os << "# inflow: " << buffer_.size() << " buffer particles moving with the fluid at the inlet (velocity extrapolated "
       << "per lane) along " << (sign_ > 0 ? "+" : "-") << axes[axis_] << " through the inlet " << axes[axis_] << " = "
       << inlet_ << " m (buffer depth " << depth_ << " m)\n";
  else if (!buffer_.empty())
    os << "# inflow: " << buffer_.size() << " buffer particles"
       << (nozzle_radius_ > 0 ? ", a circular nozzle of radius " + std::to_string(nozzle_radius_) + " m" : std::string())
       << ", " << profile_ << " profile of mean " << mean_velocity_
       << " m/s along " << (sign_ > 0 ? "+" : "-") << axes[axis_] << " through the inlet " << axes[axis_] << " = "
       << inlet_ << " m (buffer depth " << depth_ << " m" << (ramp_time_ > 0 ? ", ramped over " : "")
       << (ramp_time_ > 0 ? std::to_string(ramp_time_) + " s" : std::string()) << ")\n";
  if (outflow_)
    os << "# outflow: fluid particles past " << axes[out_axis_] << " = " << out_position_ << " m ("
       << (out_sign_ > 0 ? "+" : "-") << axes[out_axis_] << ") are removed\n";
  return os.str();
}

// [inflow] and [outflow] (src/boundary/registry.cpp): the buffer particles appended after every
// other particle, with ids after theirs; the hook runs after the pressure scheme's.
template <int D>
void buildInflowOutflow(BoundaryBuild<D>& b) {
  std::uint64_t next_id = 0;
  for (std::uint64_t ident : b.particles.id) next_id = std::max(next_id, ident + 1);
  auto flow = InflowOutflow<D>::fromConfig(b.root, b.particles, b.domain, b.spacing, b.rest_density, b.support,
                                           next_id);
  if (!flow) return;
  b.facts.open = true;
  b.facts.inflow_buffer = flow->hasBuffer();
  b.facts.extrapolated_inflow = flow->extrapolatedVelocity();
  b.facts.prescribed_peak_speed = flow->prescribedPeakSpeed();
  if (flow->hasBuffer()) {
    const Vec<D> e = flow->flowDirection();
    for (int a = 0; a < D; ++a)
      if (e[a] != 0) {
        b.facts.inflow_axis = a;
        b.facts.inflow_sign = e[a];
      }
  }
  b.hooks.push_back(std::move(flow));
}

template void buildInflowOutflow<2>(BoundaryBuild<2>&);
template void buildInflowOutflow<3>(BoundaryBuild<3>&);

template class InflowOutflow<2>;
template class InflowOutflow<3>;

}  // namespace vesph
