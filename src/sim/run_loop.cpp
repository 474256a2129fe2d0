// The run loop (docs/architecture.md "The life of one step"): from the initial state (or a
// checkpoint, --resume) to the end time, a frame and a checkpoint at every output time, the
// diagnostics and checks after every accepted step (RunLoop is the StepObserver the integrator's
// system hands every accepted step to), and the ending: the failure handling (the last good state
// as the last frame), interruption, and summary.json.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <sstream>

#include "vesph/io/progress.hpp"
#include "vesph/sim/integrated_system.hpp"
#include "vesph/sim/simulation.hpp"

namespace vesph {

template <int D>
class RunLoop final : public StepObserver {
 public:
  RunLoop(Simulation<D>& sim, const RunOptions& opt)
      : sim_(sim), opt_(opt), t_start_(Clock::now()), distribution_(sim.system_.distribution.get()),
        root_(distribution_ == nullptr || distribution_->rank() == 0),
        // --resume: the checkpoint of the earlier segment replaces the initial state.
        resumed_(opt.resume ? sim.checkpoints_.resume(opt.output_dir, resumeRules()) : Checkpoint{}),
        t0_(resumed_.time), writer_(openWriter()), scratch_(sim.state_.size()),
        steps_(static_cast<std::uint64_t>(resumed_.step)), max_dev_seen_(resumed_.max_density_deviation),
        progress_(t0_, sim.t_end_, opt.quiet), ode_(sim.system_, sim.state_, *this) {}

  RunReport run();
  bool accepted(double t, double dt, const double* y) override;
  bool stepCollapsed(double t, double dt);
  bool writtenFieldsFinite() const;
  bool locallyFinite() const;

 private:
  using Clock = std::chrono::steady_clock;
  ResumeRules resumeRules() const;
  std::unique_ptr<OutputWriter<D>> openWriter() const;
  Checkpoint totals(double t) const;
  bool writeFrame(double t, bool only_if_finite = false);
  void integrate(RunStatus& status, std::string& message);
  void startIntegration();
  void writeLastGood(std::string& message);
  nlohmann::json summary(const RunReport& report);

  Simulation<D>& sim_;
  const RunOptions& opt_;
  const Clock::time_point t_start_;
  // A run across processes (docs/architecture.md "Distributed runs"): every process writes its
  // share of each frame into the one file; process 0 writes the summary and the progress.
  ParticleDistribution<D>* const distribution_;
  const bool root_;
  const Checkpoint resumed_;
  const double t0_;
  std::unique_ptr<OutputWriter<D>> writer_;
  std::vector<DiagnosticsRow> pending_;  // rows of the steps since the last frame
  std::vector<double> scratch_;
  std::uint64_t steps_;  // accepted and checked, the earlier segments' included
  double max_dev_seen_;
  std::string failure_;
  Progress progress_;
  double last_frame_time_ = -1;
  bool interrupted_ = false;  // some process was interrupted (accepted() stopped the run)
  IntegratedSystem<D> ode_;
};

template <int D>
ResumeRules RunLoop<D>::resumeRules() const {
  return {sim_.header_.name, sim_.resolved_scene_, sim_.t_end_, sim_.checks_.removes_leaving, sim_.checks_.max_speed};
}

template <int D>
std::unique_ptr<OutputWriter<D>> RunLoop<D>::openWriter() const {
  if (opt_.output_dir.empty()) return nullptr;
  const SphSystem<D>& sys = sim_.system_;
  const FileAttributes attrs{D, sim_.resolved_scene_, sim_.dx_, sys.kernel.h, std::string(kernelName(sys.kernel.type)),
                             StepChecks<D>::hookColumns(sys), sim_.gauges_.series()};
  // A run across processes: every process opens the file and writes its share of each frame.
  const void* together = distribution_ ? distribution_->communicator() : nullptr;
  return opt_.resume ? std::make_unique<OutputWriter<D>>(opt_.output_dir, sim_.header_.name, attrs, t0_, together)
                     : std::make_unique<OutputWriter<D>>(opt_.output_dir, sim_.header_.name, attrs, together);
}

// The run's totals include the earlier segments of a resumed run.
template <int D>
Checkpoint RunLoop<D>::totals(double t) const {
  const IntegratorStats st = sim_.integrator_->stats();
  Checkpoint c;
  c.time = t;
  c.step = static_cast<std::int64_t>(steps_);
  c.rhs_evals = resumed_.rhs_evals + st.rhs_evals;
  c.rejected_steps = resumed_.rejected_steps + st.rejected_steps;
  c.neighbour_builds = resumed_.neighbour_builds + sim_.system_.neighbours.builds();
  c.wall_seconds = resumed_.wall_seconds + std::chrono::duration<double>(Clock::now() - t_start_).count();
  c.max_density_deviation = max_dev_seen_;
  c.resumes = resumed_.resumes + (opt_.resume ? 1 : 0);
  if (distribution_) {  // the same on every process (they write the file's attributes together)
    c.neighbour_builds = static_cast<std::uint64_t>(distribution_->max(static_cast<double>(c.neighbour_builds)));
    c.wall_seconds = distribution_->max(c.wall_seconds);
  }
  return c;
}

// A frame of the current state at time t, and its restart point. Derived fields (pressure,
// wall values) come from an evaluation at the state. only_if_finite (the last good state after
// a failure): a state whose written fields are not all finite is not written (returns false).
template <int D>
bool RunLoop<D>::writeFrame(double t, bool only_if_finite) {
  if (opt_.output_dir.empty() || t == last_frame_time_) return true;  // that state is written already
  const std::vector<double>& y = sim_.state_.values();
  scratch_.resize(y.size());  // the particle count may have changed (inflow, outflow)
  sim_.system_.unpack(y.data());
  sim_.system_.evaluate(t, y.data(), scratch_.data());
  if (!writtenFieldsFinite()) {
    if (only_if_finite) return false;
    // The state passed the step checks but its pressure or stress is not finite (an overflow in
    // the equation of state): a divergence, not a frame.
    std::ostringstream os;
    os << "non-finite pressure or stress in the frame at t = " << t << " s";
    throw SharedNumericalFailure(os.str());  // writtenFieldsFinite is every process's answer
  }
  last_frame_time_ = t;
  SphSystem<D>& sys = sim_.system_;
  // The gauges from the particle set (its pressure from the evaluation above).
  if (!sim_.gauges_.empty())
    writer_->appendGauges(sim_.gauges_.evaluate(t, sys.particles, sys.kernel, sys.domain, distribution_));
  if (!distribution_) {
    writer_->writeFrame(t, static_cast<std::int64_t>(steps_), sys.particles, pending_);
    writer_->writeCheckpoint(sim_.checkpoints_.at(t, totals(t)));
  } else {
    // A run across processes: the owned particles, their checkpoint rows with them, are dealt
    // out by id (each process then writes one run of the frame's rows, in a serial run's order)
    // and every process writes its share of the one file.
    const Checkpoint local = sim_.checkpoints_.at(t, totals(t));
    ParticleSet<D> owned = distribution_->owned(sys.particles);
    sim_.checkpoints_.attachRows(owned, local);
    const OutputShare<D> share = distribution_->deal(std::move(owned));
    const CheckpointRows checkpoint_rows = sim_.checkpoints_.shareLayout(share);
    writer_->writeFrame(t, static_cast<std::int64_t>(steps_), share.particles, pending_, &checkpoint_rows.rows);
    writer_->writeCheckpoint(sim_.checkpoints_.shareCheckpoint(share, local), &checkpoint_rows);
  }
  pending_.clear();
  return true;
}

// Whether every value a frame writes is finite: the state's (positions, velocities, densities)
// and the derived fields of every particle (pressure, stresses).
template <int D>
bool RunLoop<D>::writtenFieldsFinite() const {
  const bool here = locallyFinite();
  return distribution_ ? distribution_->sum(static_cast<std::uint64_t>(here ? 0 : 1)) == 0 : here;
}

template <int D>
bool RunLoop<D>::locallyFinite() const {
  const ParticleSet<D>& p = sim_.system_.particles;
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  if (!finite(p.position) || !finite(p.velocity) || !finite(p.density)) return false;
  if (!finite(p.mass)) return false;
  for (const char* name : {"pressure", "extra_stress", "elastic_stress_zz"})  // as OutputWriter writes them
    if (const Field* f = p.fields.find(name); f && f->range == Field::Range::all && !finite(f->data)) return false;
  return true;
}

// The step floor (docs/user-guide.md "Exit codes"): a step under kStepFloor * time.end set by a
// stability limit means the run cannot reach its end (absurd coefficients drove the step to 0
// or 1e-311 and the run never ended). A tiny step that only lands on an output time (the limits
// are larger) is not a collapse. Sets failure_ naming the step and the limit.
template <int D>
bool RunLoop<D>::stepCollapsed(double t, double dt) {
  const double floor = kStepFloor * sim_.t_end_;
  const StepLimits l = sim_.integrator_->limits();
  if (!(l.smallest() < floor)) return false;
  const std::pair<const char*, double> named[] = {
      {"acoustic", l.acoustic}, {"viscous", l.viscous}, {"force", l.force}, {"relaxation", l.relaxation}};
  const auto* smallest = std::min_element(std::begin(named), std::end(named),
                                          [](const auto& a, const auto& b) { return a.second < b.second; });
  std::ostringstream os;
  os << "step " << steps_ + 1 << " (t = " << t << " s) was " << dt << " s, below the step floor " << kStepFloor
     << " time.end = " << floor << " s; the " << smallest->first << " limit set it (" << smallest->second
     << " s; acoustic " << l.acoustic << ", viscous " << l.viscous << ", force " << l.force << ", relaxation "
     << l.relaxation << " s)";
  failure_ = os.str();
  return true;
}

template <int D>
bool RunLoop<D>::accepted(double t, double dt, const double* y) {
  const DiagnosticsRow row = sim_.checks_.diagnostics(sim_.system_, t, dt, y);
  failure_ = sim_.checks_.failure(sim_.system_, row, y);
  if (!failure_.empty()) return false;
  if (dt < kStepFloor * sim_.t_end_ && stepCollapsed(t, dt)) return false;
  ++steps_;
  max_dev_seen_ = std::max(max_dev_seen_, row.max_density_deviation);
  pending_.push_back(row);
  sim_.state_.keepGood(t, y);
  if (opt_.progress && root_) progress_.update(t, steps_, dt);
  // A run across processes stops on every process when one was interrupted (mpiexec passes the
  // signal on, but it need not arrive between the same two steps everywhere).
  const bool interrupted = distribution_ ? distribution_->max(interruptRequested() ? 1.0 : 0.0) > 0 : interruptRequested();
  if (interrupted) {
    interrupted_ = true;
    return false;
  }
  if (opt_.max_steps && steps_ >= opt_.max_steps) return false;
  return true;
}

// The hooks' start and the integrator's, each followed on --resume by what the checkpoint
// carries for it (it replaces what their start computed from the state alone: the ISPH pressure
// the incremental form starts from, the hooks' totals, the integrator's rate; a hook's arrays
// are absent from a checkpoint written before the hook was switched on).
template <int D>
void RunLoop<D>::startIntegration() {
  sim_.system_.releaseWholeScene();  // kept for a resume only (SphSystem::takeWholeScene)
  sim_.system_.startHooks(t0_, sim_.state_.data());
  if (opt_.resume) sim_.checkpoints_.restore(resumed_, RestoreStage::hooks_started);
  sim_.integrator_->start(ode_, t0_, sim_.state_.data());
  if (opt_.resume) {
    last_frame_time_ = t0_;  // the checkpoint's frame is in the file already
    sim_.checkpoints_.restore(resumed_, RestoreStage::integrator_started);
  } else {
    writeFrame(0.0);
  }
}

template <int D>
void RunLoop<D>::integrate(RunStatus& status, std::string& message) {
  startIntegration();
  Integrator& integrator = *sim_.integrator_;
  for (double tout : sim_.output_times_) {
    if (tout <= t0_ * (1 + 1e-12)) continue;  // written by the earlier segment
    if (!integrator.advance(tout)) break;
    writeFrame(tout);
  }
  if (!failure_.empty()) {
    status = RunStatus::diverged;
    message = failure_;
  } else if (interrupted_ || (!distribution_ && interruptRequested())) {
    status = RunStatus::interrupted;
    message = "interrupted at t = " + std::to_string(integrator.time()) + " s; the current state is the last frame";
    writeFrame(integrator.time());
  } else if (opt_.max_steps && steps_ >= opt_.max_steps) {
    message = "stopped after " + std::to_string(steps_) + " steps as requested";
  }
}

template <int D>
void RunLoop<D>::writeLastGood(std::string& message) {
  OdeState& state = sim_.state_;
  const double good = state.goodTime();
  state.restoreGood();
  bool written = false;
  try {
    written = writeFrame(good, true);
  } catch (const NumericalFailure&) {
  }
  // A last good frame holding inf or NaN would pass for a result (issue: a frame at t = 0 with
  // an infinite pressure on the walls): it is left out and the message says what the file ends with.
  if (written)
    message += "; the last good state (t = " + std::to_string(good) + " s) is written as the last frame";
  else if (writer_)
    message += "; the last good state (t = " + std::to_string(good) +
               " s) gives non-finite pressures or stresses and is not written; " +
               (last_frame_time_ >= 0 ? "the file ends with the frame at t = " + std::to_string(last_frame_time_) + " s"
                                      : std::string("the file holds no frame"));
}

template <int D>
RunReport RunLoop<D>::run() {
  sim_.state_.keepCurrentAsGood(t0_);
  RunStatus status = RunStatus::ok;
  std::string message;
  try {
    integrate(status, message);
  } catch (const NumericalFailure& e) {
    // A run across processes: a failure thrown inside one process's right-hand side (a model's)
    // is that process's alone; the others wait for it in the next exchange.
    if (distribution_ && !dynamic_cast<const SharedNumericalFailure*>(&e)) distribution_->abort(e.what());
    status = RunStatus::diverged;
    message = e.what();
  } catch (const InputError&) {
    throw;  // a setting that only shows at run time: exit 2, no summary of a run that never ran
  } catch (const std::exception& e) {
    // I/O and other errors: report them in summary.json too; what was written stays readable.
    // A run across processes: a failed write is every process's (OutputFailure); any other
    // error met by one process alone would leave the others waiting for it.
    if (distribution_ && !dynamic_cast<const OutputFailure*>(&e)) distribution_->abort(e.what());
    status = RunStatus::error;
    message = e.what();
  }
  if (status == RunStatus::diverged) writeLastGood(message);
  Integrator& integrator = *sim_.integrator_;
  if (opt_.progress && root_) {
    progress_.update(integrator.time(), steps_, integrator.lastStep(), true);
    progress_.finish();
  }
  RunReport report;
  report.status = status;
  report.message = message.empty() ? "finished" : message;
  report.final_time = status == RunStatus::diverged ? sim_.state_.goodTime() : integrator.time();
  report.wall_seconds = std::chrono::duration<double>(Clock::now() - t_start_).count();
  report.summary = summary(report);
  if (!opt_.output_dir.empty() && root_) {
    try {
      writeSummary(opt_.output_dir, report.summary);
    } catch (const std::exception&) {
      if (status == RunStatus::ok) throw;  // a failed run's own error is the one to report
    }
  }
  return report;
}

// summary.json (docs/user-guide.md); closes the output file.
template <int D>
nlohmann::json RunLoop<D>::summary(const RunReport& report) {
  const Checkpoint total = totals(report.final_time);
  const SphSystem<D>& sys = sim_.system_;
  nlohmann::json s;
  s["status"] = statusName(report.status);
  s["message"] = report.message;
  s["scene"] = sim_.header_.name;
  s["final_time"] = report.final_time;
  s["end_time"] = sim_.t_end_;
  s["steps"] = steps_;  // accepted steps (a step that failed the checks is not counted)
  s["rejected_steps"] = total.rejected_steps;
  s["rhs_evals"] = total.rhs_evals;
  s["neighbour_builds"] = total.neighbour_builds;
  s["wall_seconds"] = total.wall_seconds;
  if (opt_.resume)
    s["resumed"] = {{"from_time", t0_}, {"count", total.resumes}, {"segment_wall_seconds", report.wall_seconds}};
  if (distribution_) {
    const ParticleSet<D>& p = sys.particles;
    s["particles"] = distribution_->sum(static_cast<std::uint64_t>(p.ownedMoving() + p.ownedEnd() - p.n_moving));
    s["fluid_particles"] = distribution_->sum(static_cast<std::uint64_t>(p.ownedMoving()));
    s["processes"] = distribution_->size();
    s["redistributions"] = distribution_->redistributions();
    s["repartitions"] = distribution_->repartitions();
    s["load_imbalance"] = distribution_->imbalance();
    const DistributionCounters c = distribution_->counters();
    s["distribution"] = {{"ghosts", c.ghosts},
                         {"neighbour_links", c.neighbour_links},
                         {"halo_refreshes", c.refreshes},
                         {"halo_messages", c.messages},
                         {"halo_bytes", c.bytes},
                         {"particles_migrated", c.migrated}};
  } else {
    s["particles"] = sys.particles.size();
    s["fluid_particles"] = sys.particles.n_moving;
  }
  s["integrator"] = sim_.integrator_name_;
  s["threads"] = omp_get_max_threads();
  s["max_density_deviation"] = max_dev_seen_;
  s["scheme"] = std::string(sim_.scheme_->name());
  for (const auto& hk : sys.hooks) hk->summarize(s);
  if (const PressureModel* m = sys.pressureModel()) {
    s["sound_speed"] = m->soundSpeed();
    if (m->designDensityVariation() > 0) s["design_density_variation"] = m->designDensityVariation();
  }
  if (writer_) {
    s["frames"] = writer_->frames();
    s["h5"] = std::filesystem::path(writer_->h5Path()).filename().string();
    s["xdmf"] = std::filesystem::path(writer_->xdmfPath()).filename().string();
    writer_.reset();
  }
  return s;
}

template <int D>
RunReport Simulation<D>::run(const RunOptions& options) {
  return RunLoop<D>(*this, options).run();
}

template RunReport Simulation<2>::run(const RunOptions&);
template RunReport Simulation<3>::run(const RunOptions&);

}  // namespace vesph
