#pragma once
// Scene -> Simulation (DESIGN.md "The shape"). Building reads and validates every key of the
// scene (unknown keys, wrong types, unphysical values are InputError), generates the
// particles, constructs the effects the scene lists and nothing else, and the integrator.
// run() integrates to the end time, writing frames at the output times, diagnostics after
// every step and summary.json at the end, also on failure or interruption.
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vesph/io/config.hpp"
#include "vesph/io/output.hpp"
#include "vesph/boundary/dummy_walls.hpp"
#include "vesph/sim/system.hpp"

namespace vesph {

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
class Simulation {
 public:
  Simulation(Config& config, const SceneHeader& header);

  RunReport run(const RunOptions& options);
  // Human-readable facts about the built scene (particle counts, h, sound speed, limits).
  std::string describe() const;

  SphSystem<D>& system() { return system_; }
  const SphSystem<D>& system() const { return system_; }
  const std::vector<double>& state() const { return y_; }
  Integrator& integrator() { return *integrator_; }
  double spacing() const { return dx_; }
  double restDensity() const { return rho0_; }
  double endTime() const { return t_end_; }
  const std::vector<double>& outputTimes() const { return output_times_; }
  std::uint64_t neighbourPairsEvaluated() const { return system_.driver.pairsEvaluated(); }

 private:
  void generateParticles(ConfigTable& root);
  void markWallLayers();
  std::vector<WallPoint<D>> wall_points_;  // per fixed particle: its wall treatment
  DiagnosticsRow diagnostics(double t, double dt, const double* y) const;
  std::string checkState(const DiagnosticsRow& row, const double* y) const;
  std::vector<std::string> hookColumns() const;
  Checkpoint resumeFrom(const std::string& dir);

  Config& config_;
  SceneHeader header_;
  SphSystem<D> system_;
  std::unique_ptr<Integrator> integrator_;
  std::string integrator_name_;
  std::vector<double> y_, last_good_;
  double last_good_time_ = 0;
  double dx_ = 0, rho0_ = 0, mu_ = 0, t_end_ = 0;
  std::vector<double> output_times_;
  double max_density_deviation_ = 0.5, max_speed_ = 0;
  bool leave_domain_remove_ = false;  // [checks] leave_domain = "remove" (DomainExit hook)
  std::string resolved_scene_;
  std::string scheme_ = "wcsph";
  mutable std::vector<double> hook_values_;
};

}  // namespace vesph
