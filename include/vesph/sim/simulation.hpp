#pragma once
// Scene -> Simulation (docs/architecture.md "The shape" and "The life of one step"). Building
// reads and validates every key of the scene (unknown keys, wrong types, unphysical values are
// InputError), generates the particles (src/sim/particle_generation.cpp), builds the boundaries
// (src/boundary/registry.cpp), the effects the scene lists and nothing else
// (src/physics/registry.cpp), the pressure scheme (src/sim/pressure_schemes.cpp) and the
// integrator, and lists who carries what in checkpoints (src/sim/checkpoint.cpp).
// run() (src/sim/run_loop.cpp) integrates to the end time, writing frames at the output times,
// diagnostics after every step and summary.json at the end, also on failure or interruption.
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/io/config.hpp"
#include "vesph/io/output.hpp"
#include "vesph/sim/checkpoint.hpp"
#include "vesph/sim/gauges.hpp"
#include "vesph/sim/ode_state.hpp"
#include "vesph/sim/particle_generation.hpp"
#include "vesph/sim/pressure_scheme.hpp"
#include "vesph/sim/step_checks.hpp"
#include "vesph/sim/system.hpp"

namespace vesph {

// Limits `vesph check` applies so that `run` cannot fail on them later (docs/user-guide.md
// "Exit codes"): the scene name names the output files (255 bytes per file name); the output
// times are allocated before the run; the step floor: after an accepted step, a step under
// kStepFloor * time.end ends the run as diverged (it would not reach the end); the viscosity's
// bound keeps sane scenes' viscous step limit above that floor.
inline constexpr std::size_t kMaxSceneNameBytes = 200;
inline constexpr std::size_t kMaxOutputTimes = 1000000;
inline constexpr double kStepFloor = 1e-12;
inline constexpr double kMaxViscosity = 1e6;  // Pa s

// The parts of a scene that do not depend on the dimension.
struct SceneHeader {
  std::string name;
  int dimension = 2;
};
// Parses the file with the overrides and reads name and dimension.
Config loadScene(const std::string& file, const std::vector<std::string>& overrides, SceneHeader& header);

enum class RunStatus { ok, diverged, interrupted, error };
const char* statusName(RunStatus s);
int exitCode(RunStatus s);

struct RunOptions {
  std::string output_dir;  // empty: no output files (benchmarks)
  bool quiet = false;
  bool progress = true;
  std::uint64_t max_steps = 0;  // 0: run to the end time; otherwise stop after this many steps
  // Go on from the checkpoint in output_dir (the state of its last frame) instead of the
  // initial state, appending to its files (`vesph run --resume`).
  bool resume = false;
};

struct RunReport {
  RunStatus status = RunStatus::ok;
  std::string message;
  double final_time = 0;
  double wall_seconds = 0;
  nlohmann::json summary;
};

template <int D>
class RunLoop;

template <int D>
class Simulation {
 public:
  Simulation(Config& config, const SceneHeader& header);
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  RunReport run(const RunOptions& options);
  // Human-readable facts about the built scene (particle counts, h, sound speed, limits).
  std::string describe() const;
  // Per [[blocks]] table: its particle count and volume against the shape's (`vesph check`).
  std::string describeBlocks() const;
  const std::vector<BlockSummary>& blockSummaries() const { return block_summaries_; }

  SphSystem<D>& system() { return system_; }
  const SphSystem<D>& system() const { return system_; }
  const std::vector<double>& state() const { return state_.values(); }
  Integrator& integrator() { return *integrator_; }
  double spacing() const { return dx_; }
  double restDensity() const { return rho0_; }
  double endTime() const { return t_end_; }
  const std::vector<double>& outputTimes() const { return output_times_; }
  std::uint64_t neighbourPairsEvaluated() const { return system_.driver.pairsEvaluated(); }

 private:
  friend class RunLoop<D>;
  // The steps of building, in the order the scene is read (which decides the first error
  // reported in a scene with several).
  void readDomainKernelFluid(ConfigTable& root);
  void buildEffects(ConfigTable& root);
  void buildScheme(ConfigTable& root, const BoundaryFacts& facts);
  void readOutputTimes(ConfigTable& root);
  ReferenceScales referenceScales(double inflow_speed) const;
  void readChecks(ConfigTable& root, double velocity_scale, bool removes_leaving);
  void distribute();
  // The whole scene's counts in a distributed run (the system holds one process's share).
  struct WholeScene {
    std::size_t particles = 0, moving = 0;
    std::uint64_t ghosts = 0;
    int processes = 1;
    double imbalance = 1;
  } whole_scene_;

  Config& config_;
  SceneHeader header_;
  SphSystem<D> system_;
  OdeState state_;
  std::unique_ptr<PressureScheme<D>> scheme_;
  std::unique_ptr<Integrator> integrator_;
  std::string integrator_name_;
  std::vector<WallPoint<D>> wall_points_;  // per fixed particle: its wall treatment
  std::vector<BlockSummary> block_summaries_;  // per [[blocks]] table: count and volume
  double dx_ = 0, rho0_ = 0, mu_ = 0, t_end_ = 0, skin_ = 0;
  std::vector<double> output_times_;
  StepChecks<D> checks_;
  Gauges<D> gauges_;  // [[gauges]], evaluated with every frame
  Checkpoints<D> checkpoints_{system_, state_};
  std::string resolved_scene_;
};

}  // namespace vesph
