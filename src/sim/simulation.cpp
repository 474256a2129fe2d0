#include "vesph/sim/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>
#include <sstream>
#include <tuple>

#include "vesph/boundary/domain_exit.hpp"
#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/boundary/inflow_outflow.hpp"
#include "vesph/io/progress.hpp"
#include "vesph/isph/projection.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {

Config loadScene(const std::string& file, const std::vector<std::string>& overrides, SceneHeader& header) {
  Config cfg = Config::fromFile(file, overrides);
  ConfigTable root = cfg.root();
  header.name = root.string("name", std::nullopt);
  if (header.name.empty() || header.name.find_first_of("/\\ ") != std::string::npos)
    root.fail("name", "a non-empty name without spaces or slashes (it names the output files)");
  header.dimension = static_cast<int>(root.integer("dimension", 2, 2, 3));
  return cfg;
}

const char* statusName(RunStatus s) {
  switch (s) {
    case RunStatus::ok: return "ok";
    case RunStatus::diverged: return "diverged";
    case RunStatus::interrupted: return "interrupted";
    case RunStatus::error: return "error";
  }
  return "error";
}

int exitCode(RunStatus s) {
  switch (s) {
    case RunStatus::ok: return 0;
    case RunStatus::diverged: return 3;
    case RunStatus::interrupted: return 130;
    case RunStatus::error: return 1;
  }
  return 1;
}

template <int D>
Simulation<D>::Simulation(Config& config, const SceneHeader& header) : config_(config), header_(header) {
  ConfigTable root = config.root();
  root.markRead("name");
  root.markRead("dimension");

  // Domain.
  ConfigTable dom = root.table("domain", false);
  Domain<D>& domain = system_.domain;
  domain.lo = dom.vector<D>("min", std::nullopt, "m");
  domain.hi = dom.vector<D>("max", std::nullopt, "m");
  const auto periodic = dom.booleans("periodic", std::vector<bool>(D, false), D);
  for (int a = 0; a < D; ++a) {
    domain.periodic[a] = periodic[a];
    if (!(domain.hi[a] > domain.lo[a])) dom.fail("max", "a corner above domain.min along every axis");
  }

  // Particles and kernel.
  ConfigTable par = root.table("particles", false);
  dx_ = par.number("spacing", std::nullopt, Bound::positive, "m");
  std::vector<std::string> kernels = kernelNames();
  const KernelType kt = kernelFromName(par.choice("kernel", "quintic", kernels));
  const double ratio = par.numberIn("smoothing_ratio", 1.6, 0.5, 4.0, "h/dx");
  system_.kernel = Kernel(kt, D, ratio * dx_);
  const double skin = root.table("neighbours").numberIn("skin", 0.1, 0.0, 2.0, "fraction of the kernel support");

  // Fluid.
  ConfigTable fluid = root.table("fluid", false);
  rho0_ = fluid.number("density", std::nullopt, Bound::positive, "kg/m^3");
  mu_ = fluid.number("viscosity", std::nullopt, Bound::nonnegative, "Pa s");

  generateParticles(root);
  // Open boundaries (an inflow buffer of fixed particles, an outflow plane).
  std::uint64_t next_id = 0;
  for (std::uint64_t ident : system_.particles.id) next_id = std::max(next_id, ident + 1);
  auto flow = InflowOutflow<D>::fromConfig(root, system_.particles, system_.domain, dx_, rho0_,
                                           system_.kernel.supportRadius(), next_id);
  if (!wall_points_.empty()) wall_points_.resize(system_.particles.nFixed());  // buffer: no image treatment

  // Effects, boundaries.
  ConfigTable effects = root.table("effects", false);
  system_.effects = makeEffects<D>(effects);
  if (system_.effects.empty())
    effects.fail("continuity", "at least one effect, e.g. [effects.continuity]");
  if (system_.particles.nFixed() > 0)
    system_.boundaries.push_back(std::make_unique<DummyWalls<D>>(wall_points_, flow && flow->extrapolatedVelocity()));

  // Pressure scheme: weakly compressible (the pressure from an equation of state, an effect)
  // or incompressible (the projection after every step, src/isph).
  ConfigTable solver = root.table("solver");
  scheme_ = solver.choice("scheme", "wcsph", {"wcsph", "isph"});
  if (scheme_ == "isph") {
    for (const WallPoint<D>& w : wall_points_) {
      if (w.image)
        throw InputError(config_.file() + ": blocks: treatment = \"image\" walls are not implemented with solver.scheme = "
                         "\"isph\" (the projection extrapolates the wall pressure as for dummy layers); use treatment = \"dummy\"");
      if (std::isfinite(w.pressure_floor))
        throw InputError(config_.file() + ": blocks: pressure_floor is not implemented with solver.scheme = \"isph\" "
                         "(the projection solves the wall pressures with the fluid's); remove it or use scheme = \"wcsph\"");
    }
    // A prescribed inflow is a velocity inlet: for the pressure Poisson equation a Neumann
    // boundary like a wall, with the buffer's velocity in the divergence. The extrapolated
    // (pressure) inlet would need a Dirichlet pressure on the buffer, which the projection does
    // not have. Open ends need p = 0 on the particles with a cut support (free-surface
    // detection): without it the open channel diverged within 34 steps.
    if (flow && flow->extrapolatedVelocity())
      throw InputError(config_.file() + ": inflow.velocity = \"extrapolated\" is not implemented with solver.scheme = \"isph\" "
                       "(the projection takes the buffer as a Neumann boundary, right for a prescribed velocity only); "
                       "use velocity = \"prescribed\" or scheme = \"wcsph\"");
    if (flow && std::none_of(system_.effects.begin(), system_.effects.end(), [](const auto& e) { return e->name() == "free_surface"; }))
      throw InputError(config_.file() + ": inflow/outflow with solver.scheme = \"isph\" need [effects.free_surface] "
                       "(threshold = 0.97): the open ends are free surfaces with p = 0");
    if ((!flow || !flow->hasBuffer()) && solver.has("inlet_condition"))
      solver.fail("inlet_condition", "only with a prescribed [inflow] (the condition is the buffer's)");
    system_.hooks.push_back(makeProjection<D>(solver));
  } else {
    for (const std::string& key : solver.keys())
      if (key != "scheme") solver.fail(key, "no " + key + " with scheme = \"wcsph\" (the linear-solver keys belong to scheme = \"isph\")");
  }

  // A prescribed inflow knows the flow's speed: the velocity scale for default tolerances when
  // no sound-speed rule gives one (ISPH scenes).
  const double inflow_speed = flow ? flow->prescribedPeakSpeed() : 0.0;
  if (flow) system_.hooks.push_back(std::move(flow));  // after the projection (DESIGN.md hook order)
  // What happens to a fluid particle that leaves the domain: the run stops (a numerical
  // failure, the default) or the particle is removed and counted (splashes).
  leave_domain_remove_ = root.table("checks").choice("leave_domain", "stop", {"stop", "remove"}) == "remove";
  if (leave_domain_remove_) system_.hooks.push_back(std::make_unique<DomainExit<D>>());

  // Time, integrator, output, checks.
  ConfigTable time = root.table("time", false);
  t_end_ = time.number("end", std::nullopt, Bound::positive, "s");

  ConfigTable out = root.table("output");
  std::vector<double> times = out.numbers("times", std::vector<double>{}, 0, "s");
  const double interval = out.number("interval", t_end_, Bound::positive, "s");
  for (double t : times)
    if (!(t > 0 && t <= t_end_ * (1 + 1e-12))) out.fail("times", "output times in (0, time.end]");
  for (double t = interval; t < t_end_ * (1 - 1e-12); t += interval) times.push_back(t);
  times.push_back(t_end_);
  std::sort(times.begin(), times.end());
  for (double t : times)
    if (output_times_.empty() || t - output_times_.back() > 1e-12 * t_end_) output_times_.push_back(std::min(t, t_end_));

  try {
    system_.setup(dx_, rho0_, mu_, skin * system_.kernel.supportRadius());
  } catch (const InputError& e) {  // messages from effects and the domain name no file yet
    throw InputError(config.file() + ": " + e.what());
  }
  markWallLayers();

  // The integrator, with the scales for default tolerances: the sound-speed rule's design
  // velocity and density variation when the scene used it; else Mach 0.1 of the given sound
  // speed and delta = 0.01; without a pressure model (ISPH) the inflow's peak speed or the
  // fastest initial fluid speed.
  // The stress scale of evolving models uses the rule's length, else 40 dx.
  ReferenceScales scales{dx_, rho0_, 0.01, 0.0};
  double length = 40 * dx_;
  if (const PressureModel* m = system_.pressureModel()) {
    if (m->designDensityVariation() > 0) scales.density_variation = m->designDensityVariation();
    scales.velocity = m->designVelocity() > 0 ? m->designVelocity() : 0.1 * m->soundSpeed();
    if (m->designLength() > 0) length = m->designLength();
  }
  if (!(scales.velocity > 0)) scales.velocity = inflow_speed;
  if (!(scales.velocity > 0)) {
    // Else the fastest initial fluid speed (a drop's impact velocity); 0 for a fluid at rest,
    // and arkode then asks for reference_velocity.
    const ParticleSet<D>& p = system_.particles;
    for (std::size_t i = 0; i < p.n_moving; ++i) scales.velocity = std::max(scales.velocity, p.v(i).norm());
  }
  for (const auto& e : system_.effects) scales.stress = std::max(scales.stress, e->stressScale(scales.velocity, length));
  ConfigTable integ = root.table("integrator");
  integrator_ = makeIntegrator(integ, scales, scheme_ == "isph" ? kIsphDefaultCfl : kWcsphDefaultCfl);
  integrator_name_ = integrator_->name();

  ConfigTable checks = root.table("checks");
  max_density_deviation_ = checks.numberIn("max_density_deviation", 0.5, 1e-6, 10.0, "relative");
  // The default guard: the sound speed (WCSPH). Without one (ISPH), 1000 times the flow's
  // speed scale, the reference speed above or the free-fall speed sqrt(|g| L) over the domain's
  // largest extent L: a run that has blown up stops there, before the step size has collapsed
  // and the last good state is itself far from any flow; 1e30 when the scene gives no scale.
  double guard = system_.pressureModel() ? system_.pressureModel()->soundSpeed() : 0.0;
  if (!(guard > 0)) {
    double extent = 0;
    for (int a = 0; a < D; ++a) extent = std::max(extent, system_.domain.length(a));
    const double speed = std::max(scales.velocity, std::sqrt(system_.bodyAcceleration().norm() * extent));
    guard = speed > 0 ? 1e3 * speed : 1e30;
  }
  max_speed_ = checks.number("max_speed", guard, Bound::positive, "m/s");

  config.rejectUnknownKeys();
  resolved_scene_ = config.resolvedToml();

  y_.resize(system_.size());
  system_.pack(y_.data());
}

template <int D>
void Simulation<D>::generateParticles(ConfigTable& root) {
  // A block is a box (min, max: particles at the cell centres of a lattice of spacing dx) or,
  // for fluid, a disk (2D) / sphere (3D) of the given centre and diameter: the nodes
  // centre + k dx (k integer) inside the circle, the Cartesian lattice cut by the circle of
  // Fang et al. (2006) §4 (D = 2 cm, dx = 0.02 cm: 7845 particles).
  struct Box {
    ParticleKind kind;
    Vec<D> lo, hi;  // the bounding box for a disk
    std::string path;
    bool disk = false;
    Vec<D> centre = Vec<D>::Zero();
    double radius = 0;
    Vec<D> velocity = Vec<D>::Zero();
    double jitter = 0;       // fluid: random displacement of each particle, fraction of dx
    std::uint64_t seed = 1;  // of the jitter's random sequence (reproducible)
    bool image = false;      // wall: Fang et al. (2006) §3.3 boundary + image particles
    int normal_axis = 0;     // image wall: its surface faces +-e_axis (into the fluid)
    double normal_sign = 1;
    bool centroid = false;   // image wall: extrapolate from the centroid of P's weights
    double pressure_floor = -std::numeric_limits<double>::infinity();  // dummy wall, Pa
  };
  const Vec<D> v0 = root.table("initial").vector<D>("velocity", Vec<D>::Zero(), "m/s");
  std::vector<Box> boxes;
  auto blocks = root.tableArray("blocks");
  if (blocks.empty()) root.fail("blocks", "at least one [[blocks]] table with kind, min and max");
  for (ConfigTable& b : blocks) {
    const std::string kind = b.choice("kind", std::nullopt, {"fluid", "wall"});
    const std::string round_name = D == 2 ? "disk" : "sphere";
    const std::string shape = b.choice("shape", "box", {"box", round_name});
    Box box{kind == "fluid" ? ParticleKind::fluid : ParticleKind::wall, Vec<D>::Zero(), Vec<D>::Zero(), b.path()};
    if (kind == "fluid") {
      box.velocity = b.vector<D>("velocity", v0, "m/s");
      // A lattice aligned with the flow can persist as particle columns (the drop's opening,
      // docs/validation.md §10); a small random displacement breaks it. Uniform in
      // [-jitter/2, jitter/2] dx per axis; the mass stays rho0 dx^D.
      box.jitter = b.numberIn("jitter", 0.0, 0.0, 0.5, "of the particle spacing");
      box.seed = static_cast<std::uint64_t>(b.integer("seed", 1, 0, 1LL << 62));
    }
    if (shape != "box") {
      if (kind != "fluid") b.fail("shape", "\"box\" for a wall block (walls are boxes of layers)");
      box.disk = true;
      box.centre = b.vector<D>("centre", std::nullopt, "m");
      box.radius = 0.5 * b.number("diameter", std::nullopt, Bound::positive, "m");
      if (box.radius < dx_) b.fail("diameter", "at least two particle spacings");
      box.lo = box.centre.array() - box.radius;
      box.hi = box.centre.array() + box.radius;
      const Domain<D>& dom = system_.domain;
      for (int a = 0; a < D; ++a)
        if (box.lo[a] < dom.lo[a] || box.hi[a] > dom.hi[a])
          b.fail("centre", "a " + round_name + " inside the domain [domain.min, domain.max]");
      boxes.push_back(box);
      continue;
    }
    box.lo = b.vector<D>("min", std::nullopt, "m");
    box.hi = b.vector<D>("max", std::nullopt, "m");
    if (kind == "wall") {
      // Per wall: vesph's dummy layers (Adami et al. 2012) or Fang's boundary particles on the
      // wall surface plus image particles behind it (include/vesph/boundary/dummy_walls.hpp).
      box.image = b.choice("treatment", "dummy", {"dummy", "image"}) == "image";
      if (box.image) {
        std::tie(box.normal_axis, box.normal_sign) = b.coordinateAxis<D>(
            "normal", "a coordinate unit vector pointing from the wall into the fluid, e.g. [0.0, 1.0] for a floor");
        box.centroid = b.choice("extrapolation", "fang", {"fang", "centroid"}) == "centroid";
      }
      if (b.has("pressure_floor")) {
        // A wall that pushes but does not pull (at 0): theory.md §6, the die's lip in
        // docs/studies.md §5.
        if (box.image) b.fail("pressure_floor", "no pressure_floor with treatment = \"image\" (dummy layers only)");
        box.pressure_floor = b.number("pressure_floor", std::nullopt, Bound::any, "Pa");
      }
    } else if (b.has("pressure_floor")) {
      b.fail("pressure_floor", "no pressure_floor on a fluid block (it bounds a wall's pressure)");
    }
    for (int a = 0; a < D; ++a) {
      const double L = box.hi[a] - box.lo[a];
      if (!(L > 0)) b.fail("max", "a corner above min along every axis");
      const double cells = L / dx_;
      if (std::abs(cells - std::round(cells)) > 1e-6 * std::max(1.0, cells)) {
        std::ostringstream os;
        os << "an extent that is a whole number of particle spacings (" << dx_ << " m) along axis " << a
           << "; the extent " << L << " m is " << cells << " spacings";
        b.fail("max", os.str());
      }
      const Domain<D>& dom = system_.domain;
      const double tol = 1e-9 * dom.length(a);
      if (box.lo[a] < dom.lo[a] - tol || box.hi[a] > dom.hi[a] + tol)
        b.fail("max", "a block inside the domain [domain.min, domain.max]");
    }
    if (box.kind == ParticleKind::wall) {
      double thinnest = 1e300;
      for (int a = 0; a < D; ++a)
        if (!(system_.domain.periodic[a])) thinnest = std::min(thinnest, box.hi[a] - box.lo[a]);
      const double support = system_.kernel.supportRadius();
      if (thinnest < support * (1 - 1e-9)) {
        std::ostringstream os;
        os << "a wall at least one kernel support thick (" << support << " m = " << std::ceil(support / dx_ - 1e-9)
           << " layers, thesis 4.2) across its thinnest non-periodic extent, which is " << thinnest << " m";
        b.fail("max", os.str());
      }
    }
    boxes.push_back(box);
  }
  // Blocks must not overlap (a particle would sit on another).
  for (std::size_t i = 0; i < boxes.size(); ++i)
    for (std::size_t j = i + 1; j < boxes.size(); ++j) {
      bool overlap = true;
      for (int a = 0; a < D; ++a)
        overlap = overlap && std::min(boxes[i].hi[a], boxes[j].hi[a]) - std::max(boxes[i].lo[a], boxes[j].lo[a]) > 1e-9 * dx_;
      if (overlap)
        throw InputError(config_.file() + ": " + boxes[j].path + ": overlaps " + boxes[i].path +
                         (boxes[i].disk || boxes[j].disk ? " (a disk or sphere counts with its bounding box)" : ""));
    }

  const double mass = rho0_ * std::pow(dx_, D);
  ParticleSet<D>& p = system_.particles;
  std::mt19937_64 rng;
  const Box* rng_box = nullptr;
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  auto jitter = [&](const Box& b) -> Vec<D> {
    Vec<D> d = Vec<D>::Zero();
    if (b.jitter <= 0) return d;
    if (rng_box != &b) {  // each block its own sequence, from its seed
      rng.seed(b.seed);
      rng_box = &b;
    }
    for (int a = 0; a < D; ++a) d[a] = b.jitter * dx_ * unit(rng);
    return d;
  };
  std::uint64_t next_id = 0;
  for (ParticleKind pass : {ParticleKind::fluid, ParticleKind::wall})
    for (const Box& b : boxes) {
      if (b.kind != pass) continue;
      if (b.disk) {
        const long reach = static_cast<long>(std::floor(b.radius / dx_ + 1e-9));
        const double r2max = b.radius * b.radius * (1 + 1e-12);
        std::array<long, D> k;
        k.fill(-reach);
        while (true) {
          Vec<D> off;
          for (int a = 0; a < D; ++a) off[a] = static_cast<double>(k[a]) * dx_;
          if (off.squaredNorm() <= r2max) p.add(Vec<D>(b.centre + off + jitter(b)), b.velocity, rho0_, mass, pass, next_id++);
          int a = 0;
          while (a < D && ++k[a] > reach) k[a++] = -reach;
          if (a == D) break;
        }
        continue;
      }
      std::array<long, D> n;
      long total = 1;
      for (int a = 0; a < D; ++a) {
        n[a] = std::lround((b.hi[a] - b.lo[a]) / dx_);
        // An image wall: one row on the surface (the boundary particles) and one row per
        // spacing of the block's depth behind it (the image particles), Fang et al. Fig. 1.
        if (b.image && a == b.normal_axis) ++n[a];
        total *= n[a];
      }
      const std::size_t first = p.size();
      for (long k = 0; k < total; ++k) {
        long rem = k;
        Vec<D> x;
        std::array<long, D> idx;
        for (int a = 0; a < D; ++a) {
          idx[a] = rem % n[a];
          x[a] = b.lo[a] + (static_cast<double>(idx[a]) + 0.5) * dx_;
          rem /= n[a];
        }
        if (b.image) {
          const int a = b.normal_axis;
          const double surface = b.normal_sign > 0 ? b.hi[a] : b.lo[a];
          x[a] = surface - b.normal_sign * static_cast<double>(idx[a]) * dx_;
          WallPoint<D> w;
          w.image = true;
          w.normal = Vec<D>::Zero();
          w.normal[a] = b.normal_sign;
          w.depth = static_cast<double>(idx[a]) * dx_;
          w.centroid = b.centroid;
          // The boundary particle of the same column: row 0 (idx[a] = 0), same other indices.
          long kb = 0, stride = 1;
          for (int c = 0; c < D; ++c) {
            kb += stride * (c == a ? 0 : idx[c]);
            stride *= n[c];
          }
          w.boundary = static_cast<Index>(first + static_cast<std::size_t>(kb));
          wall_points_.push_back(w);
        } else if (pass == ParticleKind::wall) {
          WallPoint<D> w;
          w.pressure_floor = b.pressure_floor;
          wall_points_.push_back(w);
        }
        p.add(Vec<D>(x + jitter(b)), b.velocity, rho0_, mass, pass, next_id++);
      }
    }
  if (p.n_moving == 0) root.fail("blocks", "at least one block of kind \"fluid\"");
  // Scenes without image walls or pressure floors keep no per-wall-particle record
  // (DummyWalls treats an empty one as all dummy layers without a floor).
  if (std::none_of(wall_points_.begin(), wall_points_.end(),
                   [](const WallPoint<D>& w) { return w.image || std::isfinite(w.pressure_floor); }))
    std::vector<WallPoint<D>>().swap(wall_points_);
}

template <int D>
void Simulation<D>::markWallLayers() {
  // Wall particles within 1.5 dx of the initial fluid are "wall" (kind 1); deeper layers are
  // "dummy" (kind 2). Both are treated alike; the distinction helps when looking at output.
  ParticleSet<D>& p = system_.particles;
  const auto& list = system_.neighbours;
  const double reach2 = 2.25 * dx_ * dx_;
  for (std::size_t w = p.n_moving; w < p.size(); ++w) {
    if (p.kind[w] == static_cast<std::uint8_t>(ParticleKind::inflow)) continue;
    bool touches = false;
    for (std::size_t k = list.start[w]; k < list.split[w] && !touches; ++k) {
      const Index j = list.nbr[k];
      double r2 = 0;
      for (int a = 0; a < D; ++a) {
        const double d = system_.domain.image(a, p.position[D * w + a] - p.position[D * j + a]);
        r2 += d * d;
      }
      touches = r2 <= reach2;
    }
    p.kind[w] = static_cast<std::uint8_t>(touches ? ParticleKind::wall : ParticleKind::dummy);
  }
}

template <int D>
DiagnosticsRow Simulation<D>::diagnostics(double t, double dt, const double* y) const {
  const ParticleSet<D>& p = system_.particles;
  const std::size_t n = p.n_moving;
  const double* rho = y + n * D;
  const double* v = y + n * (D + 1);
  double ke = 0, mass = 0, vmax2 = 0, dev = 0;
  const double rho0 = rho0_;
#pragma omp parallel for reduction(+ : ke, mass) reduction(max : vmax2, dev) schedule(static) if (n >= kParallelMinimum)
  for (std::size_t i = 0; i < n; ++i) {
    double v2 = 0;
    for (int a = 0; a < D; ++a) v2 += v[D * i + a] * v[D * i + a];
    ke += 0.5 * p.mass[i] * v2;
    mass += p.mass[i];
    vmax2 = std::max(vmax2, v2);
    dev = std::max(dev, std::abs(rho[i] / rho0 - 1.0));
  }
  DiagnosticsRow row{t, dt, ke, mass, std::sqrt(vmax2), dev, {}};
  std::size_t k = 0;
  for (const auto& hk : system_.hooks) {
    hook_values_.clear();
    hk->diagnostics(hook_values_);
    for (double v : hook_values_)
      if (k < kMaxExtraDiagnostics) row.extra[k++] = v;
  }
  return row;
}

template <int D>
std::string Simulation<D>::checkState(const DiagnosticsRow& row, const double* y) const {
  std::ostringstream os;
  const std::size_t n = system_.particles.n_moving;
  if (!std::isfinite(row.kinetic_energy) || !std::isfinite(row.max_density_deviation)) {
    for (std::size_t k = 0; k < n * (2 * D + 1); ++k)
      if (!std::isfinite(y[k])) {
        const std::size_t i = k < n * D ? k / D : k < n * (D + 1) ? k - n * D : (k - n * (D + 1)) / D;
        const char* field = k < n * D ? "position" : k < n * (D + 1) ? "density" : "velocity";
        os << "non-finite " << field << " of particle id " << system_.particles.id[i] << " at t = " << row.time << " s";
        return os.str();
      }
  }
  // Evolving fields (elastic stresses) are not in the diagnostics: scan them (this also names
  // the cause when the diagnostics are non-finite but positions, densities, velocities are not).
  const std::size_t total = system_.size();
  for (std::size_t k = n * (2 * D + 1); k < total; ++k)
    if (!std::isfinite(y[k])) {
      os << "non-finite evolving field (elastic stress) at t = " << row.time << " s";
      return os.str();
    }
  if (row.max_density_deviation > max_density_deviation_) {
    os << "density deviates from the rest density by " << row.max_density_deviation * 100
       << " % (> checks.max_density_deviation = " << max_density_deviation_ * 100 << " %) at t = " << row.time << " s";
    return os.str();
  }
  if (row.max_speed > max_speed_) {
    os << "a particle moves at " << row.max_speed << " m/s, faster than checks.max_speed = " << max_speed_
       << " m/s (by default the sound speed; for ISPH 1000 times the flow speed scale) at t = " << row.time << " s";
    return os.str();
  }
  for (std::size_t i = 0; i < n && !leave_domain_remove_; ++i)
    if (!system_.domain.insideNonPeriodic(y + D * i)) {
      os << "fluid particle id " << system_.particles.id[i] << " left the domain at t = " << row.time << " s";
      return os.str();
    }
  return {};
}

template <int D>
std::string Simulation<D>::describe() const {
  std::ostringstream os;
  const auto& p = system_.particles;
  const StabilitySnapshot s = system_.stability();
  os << "# scene '" << header_.name << "': " << D << "D, " << p.size() << " particles (" << p.n_moving
     << " fluid, " << p.nFixed() << " fixed)\n"
     << "# dx = " << dx_ << " m, h = " << system_.kernel.h << " m, kernel " << kernelName(system_.kernel.type)
     << " (support " << system_.kernel.supportRadius() << " m)\n";
  if (const PressureModel* m = system_.pressureModel()) {
    os << "# sound speed c = " << m->soundSpeed() << " m/s";
    if (m->designDensityVariation() > 0) os << " (density variation delta = " << m->designDensityVariation() << ")";
    os << "\n";
  }
  os << "# effects:";
  for (const auto& e : system_.effects) os << ' ' << e->name();
  os << "\n# pressure scheme " << scheme_ << "\n";
  for (const auto& hk : system_.hooks) os << hk->describe();
  os << "# integrator " << integrator_name_ << "; output at " << output_times_.size() << " times up to "
     << t_end_ << " s\n";
  os << "# stability inputs: h = " << s.h << " m, c = " << s.sound_speed << " m/s, nu = " << s.kinematic_viscosity
     << " m^2/s, |g| = " << system_.bodyAcceleration().norm() << " m/s^2\n";
  return os.str();
}

// --resume: the checkpoint in `dir` replaces the initial state (y_, the particle set, the
// between-step arrays of effects). Everything is checked before a file is touched: a refused
// resume is invalid input (exit 2). Returns the checkpoint's totals and carried arrays; its
// state has moved into y_. What hooks and the integrator carry is restored after their start
// (run()), which would otherwise overwrite it.
template <int D>
Checkpoint Simulation<D>::resumeFrom(const std::string& dir) {
  ResumeSource src = readResumeSource(dir, header_.name);
  const std::string where = dir + "/" + header_.name + ".h5";
  const std::string diff = firstSceneDifference(src.scene_toml, resolved_scene_, {"time", "output", "checks", "integrator"});
  if (!diff.empty())
    throw InputError("--resume: the scene differs from the one " + where + " was written with at '" + diff +
                     "'; only [time], [output], [checks] and [integrator] may change between the segments of a run");
  Checkpoint& ck = src.checkpoint;
  auto find = [&](const std::string& aname) { return ck.find(aname); };
  auto anotherSet = [&]() {
    return InputError("--resume: the checkpoint in " + where + " belongs to another particle set (" +
                      std::to_string(ck.id.size()) + " particles, state of " + std::to_string(ck.state.size()) +
                      " values; the scene builds " + std::to_string(system_.particles.size()) + " and " +
                      std::to_string(y_.size()) + ")");
  };
  if (!(ck.time < t_end_ * (1 + 1e-12)))
    throw InputError("--resume: the checkpoint is at t = " + std::to_string(ck.time) + " s, beyond time.end = " +
                     std::to_string(t_end_) + " s; raise time.end to go on");
  if (system_.mayResize()) {
    // The moving set of the checkpoint (released particles in, removed ones out), the fixed
    // particles' positions and velocities (the inflow buffer moves), the next id and the
    // hooks' totals.
    const std::vector<double>* n_moving = find("particles.n_moving");
    // Without it, a checkpoint of a segment whose particle set could not change (written
    // before checks.leave_domain was switched to "remove"): the set must be the scene's own
    // (checked below with every checkpoint).
    if (n_moving) {
      const std::vector<double>* position = find("particles.position");
      const std::vector<double>* velocity = find("particles.velocity");
      const std::vector<double>* mass = find("particles.mass");
      const std::vector<double>* next_id = find("system.next_id");
      if (n_moving->size() != 1 || !position || !velocity || !mass || !next_id || next_id->size() != 1)
        throw InputError("--resume: the checkpoint in " + where + " lacks part of the particle set of a scene whose particles change");
      // The fixed particles never change; their ids are checked below with the whole set.
      const std::size_t nm = static_cast<std::size_t>((*n_moving)[0]);
      if (nm > ck.id.size() || ck.id.size() - nm != system_.particles.nFixed()) throw anotherSet();
      system_.rebuildMovingSet(std::vector<std::uint64_t>(ck.id.begin(), ck.id.begin() + static_cast<std::ptrdiff_t>(nm)));
      ParticleSet<D>& p = system_.particles;
      if (position->size() != p.position.size() || velocity->size() != p.velocity.size() || mass->size() != p.mass.size())
        throw anotherSet();
      p.position = *position;
      p.velocity = *velocity;
      p.mass = *mass;
      system_.setNextId(static_cast<std::uint64_t>((*next_id)[0]));
      y_.assign(system_.size(), 0.0);
    }
  }
  if (find("domain_exit.escaped") && !leave_domain_remove_)
    throw InputError("--resume: the run in " + where + " removes particles that leave the domain; "
                     "checks.leave_domain cannot go back to \"stop\" (its diagnostics column would end)");
  if (ck.id != system_.particles.id || ck.state.size() != y_.size()) throw anotherSet();
  // Between-step arrays of effects (the lagged SOF acceleration) go back where they were.
  for (auto& e : system_.effects)
    e->restoreCarried([&](const std::string& aname) { return find(std::string(e->name()) + "." + aname); });
  y_ = std::move(ck.state);
  system_.unpack(y_.data());
  return std::move(src.checkpoint);
}

template <int D>
RunReport Simulation<D>::run(const RunOptions& opt) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  RunReport report;
  // --resume: the checkpoint of the earlier segment replaces the initial state.
  const Checkpoint resumed = opt.resume ? resumeFrom(opt.output_dir) : Checkpoint{};
  const double t0 = resumed.time;
  std::unique_ptr<OutputWriter<D>> writer;
  if (!opt.output_dir.empty()) {
    const FileAttributes attrs{D, resolved_scene_, dx_, system_.kernel.h, std::string(kernelName(system_.kernel.type)), hookColumns()};
    writer = opt.resume ? std::make_unique<OutputWriter<D>>(opt.output_dir, header_.name, attrs, t0)
                        : std::make_unique<OutputWriter<D>>(opt.output_dir, header_.name, attrs);
  }
  std::vector<DiagnosticsRow> pending;
  std::vector<double> scratch(y_.size());
  std::uint64_t steps = static_cast<std::uint64_t>(resumed.step);
  double max_dev_seen = resumed.max_density_deviation;
  std::string failure;
  Progress progress(t0, t_end_, opt.quiet);
  // The run's totals include the earlier segments of a resumed run.
  auto totals = [&](double t) {
    const IntegratorStats st = integrator_->stats();
    Checkpoint c;
    c.time = t;
    c.step = static_cast<std::int64_t>(steps);
    c.rhs_evals = resumed.rhs_evals + st.rhs_evals;
    c.rejected_steps = resumed.rejected_steps + st.rejected_steps;
    c.neighbour_builds = resumed.neighbour_builds + system_.neighbours.builds();
    c.wall_seconds = resumed.wall_seconds + std::chrono::duration<double>(Clock::now() - t_start).count();
    c.max_density_deviation = max_dev_seen;
    c.resumes = resumed.resumes + (opt.resume ? 1 : 0);
    return c;
  };
  // The restart point at a frame: the totals, the state and what is carried between steps.
  auto checkpointAt = [&](double t, const std::vector<double>& y) {
    Checkpoint c = totals(t);
    c.state = y;
    c.id = system_.particles.id;
    // What effects and hooks carry, named "<effect or hook>.<array>".
    auto carriedBy = [&](const auto& carrier) {
      NamedArrays own;
      carrier->saveCarried(own);
      for (auto& [aname, values] : own) c.arrays.emplace_back(std::string(carrier->name()) + "." + aname, std::move(values));
    };
    for (const auto& e : system_.effects) carriedBy(e);
    if (system_.mayResize()) {  // the particle set itself is part of the restart point
      const ParticleSet<D>& p = system_.particles;
      c.arrays.emplace_back("particles.n_moving", std::vector<double>{static_cast<double>(p.n_moving)});
      c.arrays.emplace_back("particles.position", p.position);
      c.arrays.emplace_back("particles.velocity", p.velocity);
      c.arrays.emplace_back("particles.mass", p.mass);
      c.arrays.emplace_back("system.next_id", std::vector<double>{static_cast<double>(system_.nextId())});
    }
    // Hooks' arrays are those of the last step taken: after a divergence (the checkpoint holds
    // the last good state) the ISPH pressure is the failed step's, which the first resumed
    // step's right-hand side sees before its projection replaces it.
    for (const auto& hk : system_.hooks) carriedBy(hk);
    // The integrator's carried rate belongs to the state it integrates, y_, which is the
    // frame's state except after a divergence (then the last good state: nothing carried).
    std::vector<double> carried = integrator_->carried();
    if (!carried.empty() && &y == &y_ && integrator_->time() == t) c.arrays.emplace_back("integrator.carried", std::move(carried));
    return c;
  };

  // Derived fields (pressure, wall values) for a frame come from an evaluation at the state.
  double last_frame_time = -1;
  auto writeFrame = [&](double t, const std::vector<double>& y) {
    if (!writer || t == last_frame_time) return;  // that state is written already
    last_frame_time = t;
    scratch.resize(y.size());  // the particle count may have changed (inflow, outflow)
    system_.unpack(y.data());
    system_.evaluate(t, y.data(), scratch.data());
    writer->writeFrame(t, static_cast<std::int64_t>(steps), system_.particles, pending);
    pending.clear();
    // Every frame is a restart point.
    writer->writeCheckpoint(checkpointAt(t, y));
  };

  last_good_ = y_;
  last_good_time_ = t0;
  system_.observer = [&](double t, double dt, double* y) {
    const DiagnosticsRow row = diagnostics(t, dt, y);
    failure = checkState(row, y);
    if (!failure.empty()) return false;
    ++steps;  // accepted and checked
    max_dev_seen = std::max(max_dev_seen, row.max_density_deviation);
    pending.push_back(row);
    const std::size_t len = y_.size();
    last_good_.resize(len);
    double* keep = last_good_.data();
#pragma omp parallel for schedule(static) if (len >= kParallelMinimumValues)
    for (std::size_t k = 0; k < len; ++k) keep[k] = y[k];
    last_good_time_ = t;
    if (opt.progress) progress.update(t, steps, dt);
    if (interruptRequested()) return false;
    if (opt.max_steps && steps >= opt.max_steps) return false;
    return true;
  };

  // After a particle-count change the last good state is the rewritten one (same time).
  system_.state_buffer = &y_;
  system_.resize_observer = [&](double t, const double* y) {
    last_good_.assign(y, y + y_.size());
    last_good_time_ = t;
  };

  RunStatus status = RunStatus::ok;
  std::string message;
  try {
    for (auto& hk : system_.hooks) hk->start(system_, t0, y_.data());
    if (opt.resume) {
      // What the hooks carry replaces what their start computed from the state alone (the
      // ISPH pressure the incremental form starts from, the hooks' totals); a hook's arrays
      // are absent from a checkpoint written before the hook was switched on.
      for (auto& hk : system_.hooks)
        hk->restoreCarried([&](const std::string& aname) { return resumed.find(std::string(hk->name()) + "." + aname); });
    }
    integrator_->start(system_, t0, y_.data());
    if (opt.resume) {
      last_frame_time = t0;  // the checkpoint's frame is in the file already
      if (const std::vector<double>* carried = resumed.find("integrator.carried")) integrator_->restoreCarried(*carried);
    }
    else writeFrame(0.0, y_);
    for (double tout : output_times_) {
      if (tout <= t0 * (1 + 1e-12)) continue;  // written by the earlier segment
      const bool reached = integrator_->advance(tout);
      if (!reached) break;
      writeFrame(tout, y_);
    }
    if (!failure.empty()) {
      status = RunStatus::diverged;
      message = failure;
    } else if (interruptRequested()) {
      status = RunStatus::interrupted;
      message = "interrupted at t = " + std::to_string(integrator_->time()) + " s; the current state is the last frame";
      writeFrame(integrator_->time(), y_);
    } else if (opt.max_steps && steps >= opt.max_steps) {
      message = "stopped after " + std::to_string(steps) + " steps as requested";
    }
  } catch (const NumericalFailure& e) {
    status = RunStatus::diverged;
    message = e.what();
  } catch (const InputError&) {
    throw;  // a setting that only shows at run time: exit 2, no summary of a run that never ran
  } catch (const std::exception& e) {
    // I/O and other errors: report them in summary.json too; what was written stays readable.
    status = RunStatus::error;
    message = e.what();
  }
  if (status == RunStatus::diverged) {
    message += "; the last good state (t = " + std::to_string(last_good_time_) + " s) is written as the last frame";
    y_ = last_good_;
    try {
      writeFrame(last_good_time_, y_);
    } catch (const NumericalFailure&) {
    }
  }
  if (opt.progress) {
    progress.update(integrator_->time(), steps, integrator_->lastStep(), true);
    progress.finish();
  }
  report.status = status;
  report.message = message.empty() ? "finished" : message;
  report.final_time = status == RunStatus::diverged ? last_good_time_ : integrator_->time();
  report.wall_seconds = std::chrono::duration<double>(Clock::now() - t_start).count();

  const Checkpoint total = totals(report.final_time);
  nlohmann::json& s = report.summary;
  s["status"] = statusName(status);
  s["message"] = report.message;
  s["scene"] = header_.name;
  s["final_time"] = report.final_time;
  s["end_time"] = t_end_;
  s["steps"] = steps;  // accepted steps (a step that failed the checks is not counted)
  s["rejected_steps"] = total.rejected_steps;
  s["rhs_evals"] = total.rhs_evals;
  s["neighbour_builds"] = total.neighbour_builds;
  s["wall_seconds"] = total.wall_seconds;
  if (opt.resume) s["resumed"] = {{"from_time", t0}, {"count", total.resumes}, {"segment_wall_seconds", report.wall_seconds}};
  s["particles"] = system_.particles.size();
  s["fluid_particles"] = system_.particles.n_moving;
  s["integrator"] = integrator_name_;
  s["threads"] = omp_get_max_threads();
  s["max_density_deviation"] = max_dev_seen;
  s["scheme"] = scheme_;
  for (const auto& hk : system_.hooks) hk->summarize(s);
  if (const PressureModel* m = system_.pressureModel()) {
    s["sound_speed"] = m->soundSpeed();
    if (m->designDensityVariation() > 0) s["design_density_variation"] = m->designDensityVariation();
  }
  if (writer) {
    s["frames"] = writer->frames();
    s["h5"] = std::filesystem::path(writer->h5Path()).filename().string();
    s["xdmf"] = std::filesystem::path(writer->xdmfPath()).filename().string();
    writer.reset();
  }
  if (!opt.output_dir.empty()) {
    try {
      writeSummary(opt.output_dir, s);
    } catch (const std::exception&) {
      if (status == RunStatus::ok) throw;  // a failed run's own error is the one to report
    }
  }
  return report;
}

template <int D>
std::vector<std::string> Simulation<D>::hookColumns() const {
  std::vector<std::string> cols;
  for (const auto& hk : system_.hooks)
    for (const std::string& c : hk->diagnosticsColumns()) cols.push_back(c);
  if (cols.size() > kMaxExtraDiagnostics) throw std::logic_error("too many diagnostics columns from hooks");
  return cols;
}

template class Simulation<2>;
template class Simulation<3>;

}  // namespace vesph
