// Gauges: the definitions in include/vesph/sim/gauges.hpp; the equations in docs/theory.md
// "Gauges". They run at output times only, over all fluid particles (a gauge is O(N), a frame
// is O(N) too), with OpenMP over particles.
#include "vesph/sim/gauges.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>

namespace vesph {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The kernel sum sum_j V_j W at a point on the free surface of a half-filled support.
constexpr double kSurfaceKernelSum = 0.5;
const char* kAxisNames[] = {"x", "y", "z"};
}  // namespace

template <int D>
void Gauges<D>::read(ConfigTable& root, const Domain<D>& domain, double spacing) {
  spacing_ = spacing;
  top_ = domain.hi[D - 1];
  if (!root.has("gauges")) return;
  std::set<std::string> names;
  for (ConfigTable& t : root.tableArray("gauges")) {
    Gauge g;
    g.name = t.string("name", std::nullopt);
    const bool valid = !g.name.empty() && g.name.size() <= 64 &&
                       std::all_of(g.name.begin(), g.name.end(), [](char c) {
                         return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
                       });
    if (!valid) t.fail("name", "a name of 1 to 64 letters, digits, '_' or '-' (it names /gauges/<name> in the output)");
    if (!names.insert(g.name).second) t.fail("name", "a name no other gauge has ('" + g.name + "' is taken)");
    const std::string type = t.choice("type", std::nullopt, {"point", "elevation", "front"});
    g.type = type == "point" ? Type::point : type == "elevation" ? Type::elevation : Type::front;
    if (g.type == Type::front) {
      if (t.has("position")) t.fail("position", "no position for a front gauge (it measures the whole fluid; axis sets its direction)");
      g.axis = static_cast<int>(t.integer("axis", 0, 0, D - 1));
    } else {
      if (t.has("axis")) t.fail("axis", "no axis for a " + type + " gauge (the front gauge's direction)");
      g.position = t.vector<D>("position", std::nullopt, "m");
      for (int a = 0; a < D; ++a)
        if (g.position[a] < domain.lo[a] || g.position[a] > domain.hi[a])
          t.fail("position", "a point inside the domain [domain.min, domain.max]");
    }
    gauges_.push_back(g);
  }
}

template <int D>
std::vector<GaugeSeries> Gauges<D>::series() const {
  std::vector<GaugeSeries> out;
  for (const Gauge& g : gauges_) {
    GaugeSeries s;
    s.name = g.name;
    s.columns = {"time"};
    switch (g.type) {
      case Type::point:
        s.type = "point";
        s.columns.push_back("pressure");
        for (int a = 0; a < D; ++a) s.columns.push_back(std::string("velocity_") + kAxisNames[a]);
        s.columns.push_back("density");
        s.columns.push_back("kernel_sum");
        break;
      case Type::elevation:
        s.type = "elevation";
        s.columns.push_back("elevation");
        break;
      case Type::front:
        s.type = "front";
        s.columns.push_back("front");
        break;
    }
    if (g.type != Type::front) s.position.assign(g.position.data(), g.position.data() + D);
    out.push_back(std::move(s));
  }
  return out;
}

// Shepard-normalised SPH interpolation at the point (docs/theory.md "Gauges").
template <int D>
void Gauges<D>::point(const Gauge& g, const ParticleSet<D>& p, const Kernel& k, const Domain<D>& dom,
                      ParticleDistribution<D>* distribution, std::vector<double>& row) const {
  const Field* pressure = p.fields.find("pressure");
  const double* pr = pressure ? pressure->data.data() : nullptr;
  const double support2 = k.supportRadius() * k.supportRadius();
  const long n = static_cast<long>(p.ownedMoving());  // a process's halo is another's
  double sum = 0, sp = 0, srho = 0, sv0 = 0, sv1 = 0, sv2 = 0;
#pragma omp parallel for reduction(+ : sum, sp, srho, sv0, sv1, sv2) schedule(static)
  for (long jj = 0; jj < n; ++jj) {
    const std::size_t j = static_cast<std::size_t>(jj);
    double r2 = 0;
    for (int a = 0; a < D; ++a) {
      const double d = dom.image(a, g.position[a] - p.position[D * j + a]);
      r2 += d * d;
    }
    if (r2 >= support2) continue;
    const double w = k.W(std::sqrt(r2)) * p.mass[j] / p.density[j];
    sum += w;
    if (pr) sp += w * pr[j];
    srho += w * p.density[j];
    sv0 += w * p.velocity[D * j];
    sv1 += w * p.velocity[D * j + 1];
    if constexpr (D == 3) sv2 += w * p.velocity[D * j + 2];
  }
  if (distribution) {
    double sums[6] = {sum, sp, srho, sv0, sv1, sv2};
    distribution->sum(sums);
    sum = sums[0], sp = sums[1], srho = sums[2], sv0 = sums[3], sv1 = sums[4], sv2 = sums[5];
  }
  const bool inside = sum > 0;
  row.push_back(inside && pr ? sp / sum : kNaN);
  const double sv[3] = {sv0, sv1, sv2};
  for (int a = 0; a < D; ++a) row.push_back(inside ? sv[a] / sum : kNaN);
  row.push_back(inside ? srho / sum : kNaN);
  row.push_back(sum);
}

// Going up the vertical line from the foot: the first height where the kernel sum falls below
// kSurfaceKernelSum after reaching it (the surface of the water column over the foot; drops and
// spray above it do not count), sampled every dx/8 with a linear interpolation of the crossing.
// NaN when the foot is dry (no water within one kernel support above it).
template <int D>
double Gauges<D>::elevation(const Gauge& g, const ParticleSet<D>& p, const Kernel& k, const Domain<D>& dom,
                            ParticleDistribution<D>* distribution) const {
  const double support = k.supportRadius(), support2 = support * support;
  // The particles within one support of the line, as (height, horizontal distance^2, volume).
  std::vector<std::array<double, 3>> near;
  for (std::size_t j = 0; j < p.ownedMoving(); ++j) {
    double h2 = 0;
    for (int a = 0; a < D - 1; ++a) {
      const double d = dom.image(a, g.position[a] - p.position[D * j + a]);
      h2 += d * d;
    }
    if (h2 < support2) near.push_back({p.position[D * j + D - 1], h2, p.mass[j] / p.density[j]});
  }
  if (distribution) {  // every process's column of particles, on every process
    std::vector<double> mine;
    for (const auto& v : near) mine.insert(mine.end(), v.begin(), v.end());
    const std::vector<double> all = distribution->allGather(mine);
    near.resize(all.size() / 3);
    for (std::size_t m = 0; m < near.size(); ++m) near[m] = {all[3 * m], all[3 * m + 1], all[3 * m + 2]};
  }
  auto kernelSum = [&](double z) {
    double s = 0;
    for (const auto& [zj, h2, v] : near) {
      const double dz = dom.image(D - 1, z - zj);
      const double r2 = h2 + dz * dz;
      if (r2 < support2) s += v * k.W(std::sqrt(r2));
    }
    return s;
  };
  const double step = spacing_ / 8;
  const double foot = g.position[D - 1];
  const long samples = static_cast<long>(std::ceil((top_ - foot) / step));
  // The foot may be on a wall, where a full water column has the kernel sum of a half support:
  // the water must start within one support above it, else the foot is dry.
  bool wet = false;
  double z = foot, below = 0;
  for (long s = 0; s <= samples; ++s) {
    const double zs = std::min(foot + static_cast<double>(s) * step, top_);
    const double here = kernelSum(zs);
    if (!wet) {
      if (here >= kSurfaceKernelSum) wet = true;
      else if (zs - foot > support) return kNaN;
    } else if (here < kSurfaceKernelSum) {
      return z + (zs - z) * (below - kSurfaceKernelSum) / (below - here);
    }
    below = here;
    z = zs;
  }
  return wet ? top_ : kNaN;
}

template <int D>
std::vector<std::vector<double>> Gauges<D>::evaluate(double t, const ParticleSet<D>& p, const Kernel& kernel,
                                                     const Domain<D>& domain,
                                                     ParticleDistribution<D>* distribution) const {
  std::vector<std::vector<double>> rows;
  for (const Gauge& g : gauges_) {
    std::vector<double> row{t};
    switch (g.type) {
      case Type::point: point(g, p, kernel, domain, distribution, row); break;
      case Type::elevation: row.push_back(elevation(g, p, kernel, domain, distribution)); break;
      case Type::front: {
        double front = -std::numeric_limits<double>::infinity();
        const long n = static_cast<long>(p.ownedMoving());
#pragma omp parallel for reduction(max : front) schedule(static)
        for (long j = 0; j < n; ++j) front = std::max(front, p.position[D * static_cast<std::size_t>(j) + g.axis]);
        if (distribution) front = distribution->max(front);
        row.push_back(std::isfinite(front) ? front : kNaN);  // no fluid particle: -inf
        break;
      }
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

template class Gauges<2>;
template class Gauges<3>;

}  // namespace vesph
