// The `vesph` command (docs/user-guide.md §2 "Command line"):
//   vesph run SCENE.toml [-o DIR] [--set KEY=VALUE]... [--quiet] [--resume] [--threads N]
//   vesph check SCENE.toml [--set KEY=VALUE]...
//   vesph list [--json]
//   vesph bench SCENE.toml [--steps N] [--threads LIST] [--set KEY=VALUE]...
// Exit codes: 0 finished, 1 other error, 2 invalid input, 3 numerical failure, 130 interrupted.
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <new>
#include <nlohmann/json.hpp>
#include <sstream>

#include "vesph/core/kernel.hpp"
#include "vesph/io/progress.hpp"
#include "vesph/physics/registry.hpp"
#include "vesph/isph/linear_solver.hpp"
#include "vesph/boundary/registry.hpp"
#include "vesph/sim/pressure_scheme.hpp"
#include "vesph/sim/simulation.hpp"
#include "vesph/time/integrator_factory.hpp"

using namespace vesph;

namespace {

// Peak and current resident memory of this process from /proc/self/status, in bytes.
long procStatusBytes(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(in, line))
    if (line.rfind(k, 0) == 0) return std::stol(line.substr(k.size())) * 1024;
  return -1;
}
void resetPeakMemory() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
}

template <int D>
int runScene(Config& cfg, const SceneHeader& h, const std::string& out_dir, bool quiet, bool resume) {
  Simulation<D> sim(cfg, h);
  const std::string dir = out_dir.empty() ? "output/" + h.name : out_dir;
  // A run across processes (mpirun -np N): process 0 speaks for the run.
  const bool root = !sim.system().distribution || sim.system().distribution->rank() == 0;
  if (!quiet && root) std::cerr << sim.describe();
  installInterruptHandlers();
  const RunReport r = sim.run(RunOptions{dir, quiet, true, 0, resume});
  if (!root) return exitCode(r.status);
  std::cerr << "vesph: " << statusName(r.status) << ": " << r.message << "\n"
            << "vesph: output in " << dir << "/ (" << h.name << ".h5, " << h.name << ".xdmf, summary.json); "
            << r.summary["steps"] << " steps, " << r.summary["rhs_evals"] << " rhs evaluations, "
            << r.wall_seconds << " s\n";
  return exitCode(r.status);
}

template <int D>
int checkScene(Config& cfg, const SceneHeader& h) {
  Simulation<D> sim(cfg, h);
  if (sim.system().distribution && sim.system().distribution->rank() != 0) return 0;  // process 0 speaks
  std::cout << sim.describe() << sim.describeBlocks() << cfg.resolvedToml() << "\n";
  return 0;
}

template <int D>
int benchScene(const std::string& file, const std::vector<std::string>& sets, std::uint64_t steps,
               const std::vector<int>& threads, int repeat) {
  // Shared machines are noisy: each thread count runs `repeat` times; the table gives the
  // fastest repetition and the median pair rate.
  std::printf("%-8s %10s %8s %10s %16s %14s %14s %14s %12s %14s\n", "threads", "particles", "steps", "wall_s",
              "particle_steps/s", "pairs/s", "median_pairs/s", "pairs/rhs", "peak_MiB", "bytes/particle");
  const long base = procStatusBytes("VmRSS");  // before any scene is built
  for (int t : threads) {
    omp_set_num_threads(t);
    std::vector<double> rates;
    double best_wall = 1e300, n = 0, st = 0, pairs_per_rhs = 0;
    long peak = 0;
    for (int r = 0; r < repeat; ++r) {
      SceneHeader h;
      Config cfg = loadScene(file, sets, h);
      resetPeakMemory();
      Simulation<D> sim(cfg, h);
      const RunReport rep = sim.run(RunOptions{"", true, false, steps});
      if (rep.status != RunStatus::ok) {
        std::fprintf(stderr, "vesph bench: the run ended with status %s: %s\n", statusName(rep.status), rep.message.c_str());
        return exitCode(rep.status);
      }
      const double pairs = static_cast<double>(sim.neighbourPairsEvaluated());
      rates.push_back(pairs / rep.wall_seconds);
      if (rep.wall_seconds < best_wall) {
        best_wall = rep.wall_seconds;
        n = static_cast<double>(sim.system().particles.size());
        st = rep.summary["steps"].get<double>();
        pairs_per_rhs = pairs / rep.summary["rhs_evals"].get<double>();
        peak = procStatusBytes("VmHWM");
      }
    }
    std::sort(rates.begin(), rates.end());
    std::printf("%-8d %10.0f %8.0f %10.3f %16.4g %14.4g %14.4g %14.4g %12.1f %14.0f\n", t, n, st, best_wall,
                n * st / best_wall, rates.back(), rates[rates.size() / 2], pairs_per_rhs, peak / 1048576.0,
                (peak - base) / n);
  }
  std::printf("# best of %d repetitions per thread count (median pair rate beside it)\n"
              "# pairs/s: directed neighbour pairs inside the kernel support handed to the pair passes per wall second\n"
              "# (the Newtonian WCSPH scene has one pair pass per rhs evaluation); bytes/particle: (peak RSS of the fastest\n"
              "# repetition - RSS before the first scene was built) / particles\n", repeat);
  return 0;
}

// What `vesph list` names besides the registries, with the summary it prints (a '\n' in a
// summary continues it on the next line).
struct Description {
  const char* name;
  const char* summary;
};
const std::vector<Description>& kernelDescriptions() {
  static const std::vector<Description> kernels = {
      {"cubic", "cubic spline, thesis eq. (3.3), support 2h"},
      {"quintic", "quintic spline, thesis eq. (3.4), support 3h"},
      {"wendland_c2", "Wendland C2, support 2h"},
  };
  return kernels;
}
int listAll() {
  std::cout << "effects (scene tables [effects.<name>]):\n";
  for (const auto& e : effectRegistry<2>()) std::printf("  %-20s %s\n", e.name.c_str(), e.summary.c_str());
  std::cout << "integrators (integrator.type):\n";
  for (const auto& e : integratorRegistry()) std::printf("  %-20s %s\n", e.name.c_str(), e.summary.c_str());
  std::cout << "Butcher tables (integrator.table, for arkode and arkode-fixed; SUNDIALS names without ARKODE_):\n";
  for (const auto& t : erkTables())
    std::printf("  %-24s order %d, %s, %d stages%s\n", t.name.c_str(), t.order,
                t.embedding_order ? ("embedding order " + std::to_string(t.embedding_order)).c_str() : "no embedding",
                t.stages, t.embedding_order ? "" : " (arkode-fixed only)");
  std::cout << "IMEX pairs (integrator.table, for arkode-imex and arkode-imex-fixed; the pair's name or either table's):\n";
  for (const auto& p : arkPairs())
    std::printf("  %-24s order %d, embedding order %d, %d stages: %s + %s\n", p.name.c_str(), p.order, p.embedding_order,
                p.stages, p.explicit_table.c_str(), p.implicit_table.c_str());
  std::cout << "kernels (particles.kernel):\n";
  for (const auto& k : kernelDescriptions()) std::printf("  %-20s %s\n", k.name, k.summary);
  std::cout << "pressure schemes (solver.scheme):\n";
  for (const auto& s : pressureSchemeRegistry<2>()) std::printf("  %-20s %s\n", s.name.c_str(), s.summary.c_str());
  std::cout << "linear solvers (solver.linear_solver, with scheme = \"isph\"):\n";
  for (const auto& s : linearSolverRegistry()) std::printf("  %-20s %s\n", s.name.c_str(), s.summary.c_str());
  std::cout << "boundaries:\n";
  for (const auto& b : boundaryRegistry<2>()) std::printf("  %-20s %s\n", b.name.c_str(), b.summary.c_str());
  return 0;
}

// `vesph list --json`: what `vesph list` prints, for programs (the Python post-processing in
// tools/vesph reads the step-limit coefficients and the kernels from here instead of copying
// them). Kernels come as tables of W(q) and dW/dq at h = 1 (so W(r, h) = W(r/h) / h^D and
// dW/dr = dW/dq(r/h) / h^(D+1)), sampled at q_i = support * i / kernel_table_intervals, an
// interval count that puts every knot of the piecewise profiles (q = 1, 2) on a sample, so a
// cubic Hermite interpolation of the samples is accurate to ~1e-12 relative.
int listJson() {
  using nlohmann::json;
  json out;
  out["format"] = "vesph-list-1";
  out["version"] = VESPH_VERSION;
  json effects = json::array();
  for (const auto& e : effectRegistry<2>()) effects.push_back({{"name", e.name}, {"summary", e.summary}});
  out["effects"] = effects;
  const StepControl defaults;
  json schemeCfl = json::object();  // each pressure scheme's default CFL coefficient
  for (const auto& s : pressureSchemeRegistry<2>()) schemeCfl[s.name] = s.make()->defaultCfl();
  const json step_limits = {
      {"cfl", schemeCfl},
      {"viscous_coefficient", defaults.viscous_coefficient},
      {"force_coefficient", defaults.force_coefficient},
      {"relaxation_coefficient", defaults.relaxation_coefficient},
      {"formulas",
       {{"acoustic", "cfl * h / (c + c_e + v_max)"},
        {"viscous", "viscous_coefficient * h^2 / nu"},
        {"force", "force_coefficient * sqrt(h / a_max)"},
        {"relaxation", "relaxation_coefficient * lambda"}}}};
  json integrators = json::array();
  for (const auto& e : integratorRegistry()) {
    json own = step_limits;  // an integrator with its own WCSPH default CFL coefficient
    if (e.wcsph_default_cfl > 0) own["cfl"]["wcsph"] = e.wcsph_default_cfl;
    integrators.push_back({{"name", e.name}, {"summary", e.summary}, {"default_step_limits", own}});
  }
  out["integrators"] = integrators;
  out["step_limits"] = step_limits;
  json tables = json::array();
  for (const auto& t : erkTables())
    tables.push_back({{"name", t.name}, {"order", t.order}, {"embedding_order", t.embedding_order}, {"stages", t.stages}});
  out["butcher_tables"] = tables;
  json pairs = json::array();
  for (const auto& p : arkPairs())
    pairs.push_back({{"name", p.name}, {"explicit_table", p.explicit_table}, {"implicit_table", p.implicit_table},
                     {"order", p.order}, {"embedding_order", p.embedding_order}, {"stages", p.stages}});
  out["imex_pairs"] = pairs;
  constexpr int kernel_table_intervals = 1200;
  json kernels = json::array();
  for (const auto& k : kernelDescriptions()) {
    json entry = {{"name", k.name}, {"summary", k.summary}, {"table_intervals", kernel_table_intervals}};
    json samples;
    for (int dim = 2; dim <= 3; ++dim) {
      const Kernel kernel(kernelFromName(k.name), dim, 1.0);
      entry["support"] = kernel.support_q;
      std::vector<double> w(kernel_table_intervals + 1), dw(kernel_table_intervals + 1);
      for (int i = 0; i <= kernel_table_intervals; ++i) {
        const double q = kernel.support_q * i / kernel_table_intervals;
        w[i] = kernel.W(q);
        dw[i] = kernel.dWdr(q);
      }
      samples[std::to_string(dim)] = {{"sigma", kernel.w_scale}, {"W", w}, {"dW_dq", dw}};
    }
    entry["samples"] = samples;
    kernels.push_back(entry);
  }
  out["kernels"] = kernels;
  json schemes = json::array();
  for (const auto& s : pressureSchemeRegistry<2>()) schemes.push_back({{"name", s.name}, {"summary", s.summary}});
  out["pressure_schemes"] = schemes;
  json solvers = json::array();
  for (const auto& s : linearSolverRegistry()) solvers.push_back({{"name", s.name}, {"summary", s.summary}});
  out["linear_solvers"] = solvers;
  json boundaries = json::array();
  for (const auto& b : boundaryRegistry<2>()) boundaries.push_back({{"name", b.name}, {"summary", b.summary}});
  out["boundaries"] = boundaries;
  std::cout << out.dump() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vesph: SPH solver for transient viscoelastic free-surface flows"};
  app.set_version_flag("--version", VESPH_VERSION);
  app.require_subcommand(1);
  std::string scene, out_dir;
  std::vector<std::string> sets;
  bool quiet = false, resume = false;
  std::uint64_t steps = 20;
  std::vector<int> threads;
  int run_threads = 0;  // 0: OpenMP's default (OMP_NUM_THREADS, else every core)
  int repeat = 3;

  auto* run = app.add_subcommand("run", "run a scene, writing DIR/<name>.h5, .xdmf and summary.json");
  run->add_option("scene", scene, "scene file (TOML)")->required();
  run->add_option("-o,--output", out_dir, "output directory (default output/<scene name>)");
  run->add_option("--set", sets, "override a scene key: --set fluid.viscosity=1e-3 (repeatable)");
  run->add_flag("--quiet", quiet, "plain periodic progress lines instead of a live display");
  run->add_flag("--resume", resume,
                "go on from the last frame of the run in DIR (its checkpoint), appending to its files; only [time], "
                "[output], [checks] and [integrator] may differ from that run's scene");
  // Up to 4096 threads: beyond any machine's cores, while a typo (--threads 40000) is refused.
  run->add_option("--threads", run_threads,
                  "OpenMP threads for the run (default: OMP_NUM_THREADS, else every core); 1 to 4096")
      ->check(CLI::Range(1, 4096));

  auto* check = app.add_subcommand("check", "validate a scene and print it with every default resolved");
  check->add_option("scene", scene, "scene file (TOML)")->required();
  check->add_option("--set", sets, "override a scene key (repeatable)");

  bool list_json = false;
  auto* list = app.add_subcommand("list", "list effects, integrators, kernels and boundaries");
  list->add_flag("--json", list_json,
                 "print them as JSON, with the default step-limit coefficients and the kernels as tables of W(q), dW/dq");

  auto* bench = app.add_subcommand("bench", "run a scene for a fixed number of steps and print throughput");
  bench->add_option("scene", scene, "scene file (TOML)")->required();
  bench->add_option("--steps", steps, "steps per measurement (default 20)");
  bench->add_option("--threads", threads, "thread counts to measure (default: 1 and all cores)")->delimiter(',');
  bench->add_option("--repeat", repeat, "repetitions per thread count; the fastest is reported (default 3)")
      ->check(CLI::Range(1, 100));
  bench->add_option("--set", sets, "override a scene key (repeatable)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }

  try {
    if (app.got_subcommand("list")) return list_json ? listJson() : listAll();
    SceneHeader h;
    if (app.got_subcommand("bench")) {
      if (threads.empty()) threads = {1, omp_get_num_procs()};
      if (threads.size() == 2 && threads[0] == threads[1]) threads.pop_back();
      loadScene(scene, sets, h);
      return h.dimension == 2 ? benchScene<2>(scene, sets, steps, threads, repeat) : benchScene<3>(scene, sets, steps, threads, repeat);
    }
    if (run_threads > 0) omp_set_num_threads(run_threads);
    Config cfg = loadScene(scene, sets, h);
    if (app.got_subcommand("check")) return h.dimension == 2 ? checkScene<2>(cfg, h) : checkScene<3>(cfg, h);
    return h.dimension == 2 ? runScene<2>(cfg, h, out_dir, quiet, resume) : runScene<3>(cfg, h, out_dir, quiet, resume);
  } catch (const InputError& e) {
    std::cerr << "vesph: invalid input: " << e.what() << "\n";
    return 2;
  } catch (const NumericalFailure& e) {
    std::cerr << "vesph: numerical failure: " << e.what() << "\n";
    return 3;
  } catch (const std::bad_alloc&) {
    // Allocations the scene asks for are estimated before they are made; this is what is left.
    std::cerr << "vesph: error: out of memory while handling " << scene << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "vesph: error: " << e.what() << "\n";
    return 1;
  }
}
