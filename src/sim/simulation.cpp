#include "vesph/sim/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "vesph/boundary/registry.hpp"
#include "vesph/parallel/communicator.hpp"
#if VESPH_HAVE_MPI_RUNS
#include "vesph/parallel/mpi_distribution.hpp"
#endif
#include "vesph/physics/registry.hpp"
#include "vesph/time/integrator_factory.hpp"
#include "vesph/sim/particle_generation.hpp"

namespace vesph {
namespace {
// Bytes of one particle in a frame: id, kind, position, velocity, density, mass, pressure, a
// symmetric stress and the free-surface flag (the output's datasets, docs/user-guide.md).
template <int D>
constexpr std::size_t bytesPerParticleFrame() {
  return 8 + 1 + 16 * D + 16 + 8 + 8 * (D * (D + 1) / 2) + 1;
}
}  // namespace

Config loadScene(const std::string& file, const std::vector<std::string>& overrides, SceneHeader& header) {
  Config cfg = Config::fromFile(file, overrides);
  ConfigTable root = cfg.root();
  header.name = root.string("name", std::nullopt);
  if (header.name.empty() || header.name.find_first_of("/\\ ") != std::string::npos)
    root.fail("name", "a non-empty name without spaces or slashes (it names the output files)");
  // The output files are <name>.h5 and <name>.xdmf (and their .tmp while written): 200 bytes
  // leave room for the suffixes under the 255 bytes a file name may have on common filesystems.
  if (header.name.size() > kMaxSceneNameBytes)
    root.fail("name", "a name of at most " + std::to_string(kMaxSceneNameBytes) +
                          " bytes (it names the output files; this one has " + std::to_string(header.name.size()) + ")");
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

// The scene builder (docs/architecture.md "The shape"): each step reads its part of the scene;
// the boundaries, effects and the pressure scheme come from their registries.
template <int D>
Simulation<D>::Simulation(Config& config, const SceneHeader& header) : config_(config), header_(header) {
  ConfigTable root = config.root();
  root.markRead("name");
  root.markRead("dimension");
  readDomainKernelFluid(root);
  std::vector<HydrostaticBlock<D>> hydrostatic_blocks;
  std::vector<BlockParticles> block_spans;
  wall_points_ = generateParticles(root, LatticeGeometry<D>{config.file(), dx_, rho0_, system_.domain, system_.kernel},
                                   system_.particles, &hydrostatic_blocks, &block_spans, &block_summaries_);
  // Walls, open boundaries (an inflow buffer of fixed particles, an outflow plane), domain exit.
  BoundaryBuild<D> boundaries{root, system_.particles, system_.domain, dx_, rho0_, system_.kernel.supportRadius(),
                              wall_points_, block_spans, {}, {}, {}};
  buildBoundaries(boundaries);
  buildEffects(root);
  system_.boundaries = std::move(boundaries.boundaries);
  buildScheme(root, boundaries.facts);
  // The boundaries' hooks after the scheme's (the projection; docs/architecture.md "The life of
  // one step": hook order).
  for (auto& hook : boundaries.hooks) system_.hooks.push_back(std::move(hook));

  ConfigTable time = root.table("time", false);
  t_end_ = time.number("end", std::nullopt, Bound::positive, "s");
  readOutputTimes(root);
  try {
    system_.setup(dx_, rho0_, mu_, skin_ * system_.kernel.supportRadius());
  } catch (const InputError& e) {  // messages from effects and the domain name no file yet
    throw InputError(config.file() + ": " + e.what());
  }
  markWallLayers(system_.particles, system_.neighbours, system_.domain, dx_);
  // The equation of state and the body acceleration are known once the system is set up.
  if (!hydrostatic_blocks.empty())
    applyHydrostaticDensity(hydrostatic_blocks, system_.pressureModel(), system_.bodyAcceleration(), rho0_,
                            config.file(), system_.particles);

  const ReferenceScales scales = referenceScales(boundaries.facts.prescribed_peak_speed);
  ConfigTable integ = root.table("integrator");
  integrator_ = makeIntegrator(integ, scales, scheme_->defaultCfl());
  // A fixed step under the step floor would be refused after the first step (exit 3): say so
  // before the run.
  if (const std::optional<double> step = integ.optionalNumber("step", Bound::positive, "s");
      step && *step < kStepFloor * t_end_) {
    std::ostringstream what;
    what << "a step of at least " << kStepFloor << " time.end = " << kStepFloor * t_end_ << " s (the step floor)";
    integ.fail("step", what.str());
  }
  integrator_name_ = integrator_->name();
  readChecks(root, scales.velocity, boundaries.facts.removes_leaving);
  gauges_.read(root, system_.domain, dx_);

  config.rejectUnknownKeys();
  resolved_scene_ = config.resolvedToml();
  if (launchedWithSeveralProcesses()) distribute();
  state_.resize(system_.size());
  system_.pack(state_.data());
  checkpoints_.joinScene();
  checkpoints_.joinIntegrator(*integrator_);
}

// A run across processes (mpirun -np N, N > 1; docs/architecture.md "Distributed runs"):
// every process has built the whole scene; the system keeps this process's share. What keeps
// particle indices or per-particle state outside the field store is not distributed yet
// (issue 36) and is refused here, before the run.
template <int D>
void Simulation<D>::distribute() {
  whole_scene_.particles = system_.particles.size();
  whole_scene_.moving = system_.particles.n_moving;
  std::vector<std::string> missing;
  for (const auto& hk : system_.hooks)
    if (!hk->distributable())
      missing.push_back("the hook " + std::string(hk->name()));
  if (std::any_of(wall_points_.begin(), wall_points_.end(), [](const WallPoint<D>& w) { return w.image; }))
    missing.push_back("image walls (treatment = \"image\": each wall particle keeps the index of its boundary particle)");
  // Every integrator runs distributed (the implicit ones' Krylov solves span the processes).
  if (!missing.empty()) {
    std::string what = config_.file() + ": a run across processes (mpirun -np N, N > 1) does not support yet (issue 36): ";
    for (std::size_t k = 0; k < missing.size(); ++k) what += (k ? "; " : "") + missing[k];
    throw InputError(what + ". Run it as one process.");
  }
#if VESPH_HAVE_MPI_RUNS
  int halo_supports = 1;
  for (const auto& hk : system_.hooks) halo_supports = std::max(halo_supports, hk->haloSupports());
  system_.distribution = makeMpiDistribution<D>(system_.domain, system_.kernel.supportRadius(),
                                                skin_ * system_.kernel.supportRadius(), 1.1, halo_supports);
  system_.distribute();
  const ParticleSet<D>& p = system_.particles;
  whole_scene_.processes = system_.distribution->size();
  whole_scene_.imbalance = system_.distribution->imbalance();
  whole_scene_.ghosts = system_.distribution->sum(static_cast<std::uint64_t>(p.n_ghost_moving + p.n_ghost_fixed));
#else
  throw InputError("this vesph was built without distributed runs (CMake option VESPH_MPI, which needs Zoltan: "
                   "libtrilinos-zoltan-dev); run it as one process");
#endif
}

template <int D>
void Simulation<D>::readDomainKernelFluid(ConfigTable& root) {
  ConfigTable dom = root.table("domain", false);
  Domain<D>& domain = system_.domain;
  domain.lo = dom.vector<D>("min", std::nullopt, "m");
  domain.hi = dom.vector<D>("max", std::nullopt, "m");
  const auto periodic = dom.booleans("periodic", std::vector<bool>(D, false), D);
  for (int a = 0; a < D; ++a) {
    domain.periodic[a] = periodic[a];
    if (!(domain.hi[a] > domain.lo[a])) dom.fail("max", "a corner above domain.min along every axis");
  }

  ConfigTable par = root.table("particles", false);
  dx_ = par.number("spacing", std::nullopt, Bound::positive, "m");
  std::vector<std::string> kernels = kernelNames();
  const KernelType kt = kernelFromName(par.choice("kernel", "quintic", kernels));
  const double ratio = par.numberIn("smoothing_ratio", 1.6, 0.5, 4.0, "h/dx");
  system_.kernel = Kernel(kt, D, ratio * dx_);
  skin_ = root.table("neighbours").numberIn("skin", 0.1, 0.0, 2.0, "fraction of the kernel support");

  ConfigTable fluid = root.table("fluid", false);
  rho0_ = fluid.number("density", std::nullopt, Bound::positive, "kg/m^3");
  // Bounded so that the viscous step limit h^2 rho / (8 mu) of a sane scene stays above the step
  // floor (docs/user-guide.md "Exit codes"); 1e6 Pa s is beyond bitumen's viscosity. 0 (the
  // default) for an inviscid fluid; the terms that need mu > 0 say so at setup.
  mu_ = fluid.numberAtMost("viscosity", 0.0, Bound::nonnegative, kMaxViscosity, "Pa s");
}

template <int D>
void Simulation<D>::buildEffects(ConfigTable& root) {
  ConfigTable effects = root.table("effects", false);
  system_.effects = makeEffects<D>(effects);
  if (system_.effects.empty()) effects.fail("continuity", "at least one effect, e.g. [effects.continuity]");
}

// The pressure scheme: weakly compressible (the pressure from an equation of state, an effect)
// or incompressible (the projection after every step, src/isph); its hooks come first.
template <int D>
void Simulation<D>::buildScheme(ConfigTable& root, const BoundaryFacts& facts) {
  ConfigTable solver = root.table("solver");
  scheme_ = makePressureScheme<D>(solver);
  SchemeBuild<D> scene{config_.file(), solver, wall_points_, facts, system_.effects, system_.hooks};
  scheme_->build(scene);
}

template <int D>
void Simulation<D>::readOutputTimes(ConfigTable& root) {
  ConfigTable out = root.table("output");
  std::vector<double> times = out.numbers("times", std::vector<double>{}, 0, "s");
  const double interval = out.number("interval", t_end_, Bound::positive, "s");
  for (double t : times)
    if (!(t > 0 && t <= t_end_ * (1 + 1e-12))) out.fail("times", "output times in (0, time.end]");
  // Counted before the list is filled: a tiny interval allocated until std::bad_alloc.
  const double from_interval = std::floor(t_end_ / interval);
  if (static_cast<double>(times.size()) + from_interval > static_cast<double>(kMaxOutputTimes)) {
    const std::size_t n = system_.particles.size();
    std::ostringstream what;
    what << "at most " << kMaxOutputTimes << " output times (output.interval and output.times give "
         << static_cast<double>(times.size()) + from_interval << "; each frame of the " << n << " particles holds about "
         << static_cast<double>(n * bytesPerParticleFrame<D>()) / 1048576.0 << " MiB)";
    out.fail(times.size() > kMaxOutputTimes ? "times" : "interval", what.str());
  }
  for (double t = interval; t < t_end_ * (1 - 1e-12); t += interval) times.push_back(t);
  times.push_back(t_end_);
  std::sort(times.begin(), times.end());
  for (double t : times)
    if (output_times_.empty() || t - output_times_.back() > 1e-12 * t_end_) output_times_.push_back(std::min(t, t_end_));
}

// The scales for the integrator's default tolerances: the sound-speed rule's design velocity
// and density variation when the scene used it; else Mach 0.1 of the given sound speed and
// delta = 0.01; without a pressure model (ISPH) a prescribed inflow's peak speed or the fastest
// initial fluid speed. The stress scale of evolving models uses the rule's length, else 40 dx.
template <int D>
ReferenceScales Simulation<D>::referenceScales(double inflow_speed) const {
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
  return scales;
}

// [checks]; the speed guard's default is the pressure scheme's (the sound speed for WCSPH, 1000
// times the flow's speed scale for ISPH).
template <int D>
void Simulation<D>::readChecks(ConfigTable& root, double velocity_scale, bool removes_leaving) {
  ConfigTable checks = root.table("checks");
  checks_.rest_density = rho0_;
  checks_.removes_leaving = removes_leaving;
  checks_.max_density_deviation = checks.numberIn("max_density_deviation", 0.5, 1e-6, 10.0, "relative");
  checks_.max_speed =
      checks.number("max_speed", scheme_->defaultSpeedGuard(system_, velocity_scale), Bound::positive, "m/s");
}

template <int D>
std::string Simulation<D>::describe() const {
  std::ostringstream os;
  const auto& p = system_.particles;
  const StabilitySnapshot s = system_.stability();
  const std::size_t all = whole_scene_.processes > 1 ? whole_scene_.particles : p.size();
  const std::size_t moving = whole_scene_.processes > 1 ? whole_scene_.moving : p.n_moving;
  os << "# scene '" << header_.name << "': " << D << "D, " << all << " particles (" << moving << " fluid, "
     << all - moving << " fixed)\n";
  if (whole_scene_.processes > 1)
    os << "# distributed over " << whole_scene_.processes << " processes (Zoltan RCB): load imbalance "
       << whole_scene_.imbalance << " (largest share of the fluid over the mean), " << whole_scene_.ghosts
       << " ghosts in all\n";
  os
     << "# dx = " << dx_ << " m, h = " << system_.kernel.h << " m, kernel " << kernelName(system_.kernel.type)
     << " (support " << system_.kernel.supportRadius() << " m)\n";
  if (const PressureModel* m = system_.pressureModel()) {
    os << "# sound speed c = " << m->soundSpeed() << " m/s";
    if (m->designDensityVariation() > 0) os << " (density variation delta = " << m->designDensityVariation() << ")";
    os << "\n";
  }
  os << "# effects:";
  for (const auto& e : system_.effects) os << ' ' << e->name();
  os << "\n# pressure scheme " << scheme_->name() << "\n";
  for (const auto& hk : system_.hooks) os << hk->describe();
  os << "# integrator " << integrator_name_ << "; output at " << output_times_.size() << " times up to "
     << t_end_ << " s\n";
  // The viscous step limit takes the largest diffusivity of the effects: the kinematic viscosity
  // nu of the viscous terms, the artificial viscosity's alpha c h / (2 (D + 2)), the density
  // diffusion's delta h c (a diffusivity of density, not a viscosity): each named by its effect.
  os << "# stability inputs: h = " << s.h << " m, c = " << s.sound_speed << " m/s, largest diffusivity "
     << s.kinematic_viscosity << " m^2/s, |g| = " << system_.bodyAcceleration().norm() << " m/s^2\n";
  for (const auto& e : system_.effects) {
    StabilityInputs own;
    e->stability(own);
    if (own.kinematic_viscosity > 0)
      os << "#   diffusivity of " << e->name() << ": " << own.kinematic_viscosity << " m^2/s"
         << (e->name() == "density_diffusion" ? " (density diffusion delta h c)"
             : e->name() == "artificial_viscosity" ? " (equivalent viscosity alpha c h / (2 (D + 2)))"
                                                   : " (kinematic viscosity nu)")
         << "\n";
  }
  return os.str();
}

template <int D>
std::string Simulation<D>::describeBlocks() const {
  std::ostringstream os;
  for (const BlockSummary& b : block_summaries_) {
    os << "# " << b.path << ": " << b.kind << " " << b.shape << ", " << b.count << " particles, volume "
       << b.volume << " m^" << D;
    if (std::isfinite(b.reference_volume) && b.reference_volume > 0)
    {
      char diff[32];
      std::snprintf(diff, sizeof diff, "%+.3f", 100.0 * (b.volume / b.reference_volume - 1.0));
      os << " (the shape's " << b.reference_volume << ", " << diff << " %)";
      // A Cartesian cut of a curved shape (a fluid disk or sphere, a hole subtracted from a
      // box) coarser than about 10 dx in radius misses its volume by more than 1 %.
      if (std::abs(b.volume / b.reference_volume - 1.0) > 0.01)
        os << "; more than 1 % off: the lattice cut is too coarse for the shape (a smaller spacing, or rings: "
              "shape = \"cylinder\")";
    }
    os << "\n";
  }
  return os.str();
}

template class Simulation<2>;
template class Simulation<3>;

}  // namespace vesph
