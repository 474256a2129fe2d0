// SUNDIALS ARKODE ERKStep integrators (SUNDIALS 6.4.1, Debian 12).
//
//   arkode        adaptive, error-controlled explicit Runge-Kutta with an embedded table;
//                 the explicit stability limits of the SPH system (stepLimits) bound the step
//                 through ERKStepSetStabilityFn with the CFL fraction set to 1, so adaptivity
//                 never steps past them.
//   arkode-fixed  the same tables in fixed-step mode, the step from the stability limits
//                 (recomputed every step) or integrator.step.
//
// The state vector of the OdeSystem is wrapped as an N_Vector without copying (serial, or the
// OpenMP N_Vector with fused operations for large states). Output times are reached with a
// stop time, so ERKStepEvolve returns the solution at tout itself, not an interpolant.
// After every accepted step a post-process function calls OdeSystem::afterStep (hooks,
// diagnostics, failure checks). Registering it also avoids SUNDIALS issue 311 (6.4.1 reuses a
// wrong right-hand side for some tables it wrongly takes as first-same-as-last): with a
// post-process function ERKStep always recomputes the first stage.
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_mpiplusx.h>
#include <nvector/nvector_openmp.h>
#include <nvector/nvector_serial.h>
#include <omp.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "sundials_support.hpp"
#include "vesph/core/types.hpp"
#include "vesph/time/integrator_factory.hpp"

namespace vesph {

N_Vector wrapState(double* y, std::size_t size, SUNContext context, const void* communicator) {
  const sunindextype n = static_cast<sunindextype>(size);
  const int threads = omp_get_max_threads();
  N_Vector v;
  if (threads > 1 && size >= 4 * kParallelMinimum) {
    v = N_VMake_OpenMP(n, y, threads, context);
    N_VEnableFusedOps_OpenMP(v, SUNTRUE);
  } else {
    v = N_VMake_Serial(n, y, context);
    N_VEnableFusedOps_Serial(v, SUNTRUE);
  }
  if (!v) throw std::runtime_error("N_VMake failed");
  if (communicator) {
    N_Vector whole = N_VMake_MPIPlusX(*static_cast<const MPI_Comm*>(communicator), v, context);
    if (!whole) throw std::runtime_error("N_VMake_MPIPlusX failed");
    return whole;
  }
  return v;
}

void destroyState(N_Vector v) {
  if (!v) return;
  // An MPIPlusX vector made over a local one does not own it.
  N_Vector local = N_VGetVectorID(v) == SUNDIALS_NVEC_MPIPLUSX ? N_VGetLocalVector_MPIPlusX(v) : nullptr;
  N_VDestroy(v);
  if (local) N_VDestroy(local);
}

void fillTolerances(double* a, std::size_t nn, const StateSegments& s, const std::vector<double>& by_segment) {
  for (std::size_t k = 0; k < nn; ++k) {
    const bool pos = k >= s.position_begin && k < s.position_end;
    const bool vel = k >= s.velocity_begin && k < s.velocity_end;
    const bool stress = k >= s.velocity_end;
    a[k] = pos ? by_segment[0] : vel ? by_segment[2] : stress ? by_segment[3] : by_segment[1];
  }
}

ErrorTolerances readTolerances(ConfigTable& cfg, const ReferenceScales& s) {
  const double rtol = cfg.numberIn("rtol", 1e-4, 1e-14, 0.5);
  // Default absolute tolerances: rtol times the scale of each field (dx for positions,
  // rho0*delta for densities, the reference velocity for velocities).
  const double vref = cfg.optionalNumber("reference_velocity", Bound::positive, "m/s").value_or(s.velocity);
  if (!(vref > 0) && !cfg.has("atol_velocity"))
    cfg.fail("reference_velocity", "the expected flow speed in m/s (for the default velocity tolerance atol_velocity = rtol * reference_velocity); "
                                   "no sound-speed rule, inflow or initial fluid velocity gives one in this scene");
  const double atol_x = cfg.number("atol_position", rtol * s.spacing, Bound::positive, "m");
  const double atol_rho = cfg.number("atol_density", rtol * s.density * s.density_variation, Bound::positive, "kg/m^3");
  const double atol_v = cfg.number("atol_velocity", rtol * vref, Bound::positive, "m/s");
  // Elastic stresses (when a model evolves them): rtol times the stress scale the model
  // declared (polymer viscosity * reference velocity / reference length).
  double atol_s = 1.0;  // unused when no stress evolves
  if (s.stress > 0) atol_s = cfg.number("atol_stress", rtol * s.stress, Bound::positive, "Pa");
  else if (cfg.optionalNumber("atol_stress", Bound::positive, "Pa"))
    cfg.fail("atol_stress", "no atol_stress: no effect of this scene evolves a stress");
  return {rtol, {atol_x, atol_rho, atol_v, atol_s}};
}

std::string arkodeFlagName(int flag) {
  char* name = ERKStepGetReturnFlagName(flag);  // ARKStepGetReturnFlagName gives the same names
  std::string s = name ? name : std::to_string(flag);
  std::free(name);
  return s;
}

void checkArkode(int flag, const char* what) {
  if (flag != ARK_SUCCESS) throw std::runtime_error(std::string("ARKODE ") + what + ": " + arkodeFlagName(flag));
}

const std::vector<ButcherTableInfo>& erkTables() {
  static const std::vector<ButcherTableInfo> tables = [] {
    // In the order of ARKODE_ERKTableID (arkode/arkode_butcher_erk.h, SUNDIALS 6.4.1).
    const char* names[] = {"HEUN_EULER_2_1_2",      "BOGACKI_SHAMPINE_4_2_3", "ARK324L2SA_ERK_4_2_3",
                           "ZONNEVELD_5_3_4",       "ARK436L2SA_ERK_6_3_4",   "SAYFY_ABURUB_6_3_4",
                           "CASH_KARP_6_4_5",       "FEHLBERG_6_4_5",         "DORMAND_PRINCE_7_4_5",
                           "ARK548L2SA_ERK_8_4_5",  "VERNER_8_5_6",           "FEHLBERG_13_7_8",
                           "KNOTH_WOLKE_3_3",       "ARK437L2SA_ERK_7_3_4",   "ARK548L2SAb_ERK_8_4_5"};
    std::vector<ButcherTableInfo> out;
    for (int id = ARKODE_MIN_ERK_NUM; id <= ARKODE_MAX_ERK_NUM; ++id) {
      ARKodeButcherTable B = ARKodeButcherTable_LoadERK(static_cast<ARKODE_ERKTableID>(id));
      if (!B) continue;
      ARKodeButcherTable byname = ARKodeButcherTable_LoadERKByName((std::string("ARKODE_") + names[id]).c_str());
      if (!byname || byname->stages != B->stages || byname->q != B->q)
        throw std::logic_error(std::string("SUNDIALS table name mismatch for ") + names[id]);
      out.push_back({names[id], id, B->q, B->d ? B->p : 0, B->stages});
      ARKodeButcherTable_Free(B);
      ARKodeButcherTable_Free(byname);
    }
    return out;
  }();
  return tables;
}

namespace {


class ArkodeErk final : public Integrator {
 public:
  ArkodeErk(bool adaptive, const ButcherTableInfo& table, const StepControl& control, double rtol,
            std::vector<double> atol_by_segment, double initial_step)
      : adaptive_(adaptive), table_(table), control_(control), rtol_(rtol),
        atol_segments_(std::move(atol_by_segment)), initial_step_(initial_step) {
    if (SUNContext_Create(nullptr, &sunctx_) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~ArkodeErk() override {
    if (mem_) ERKStepFree(&mem_);
    destroyState(y_);
    if (atol_) N_VDestroy(atol_);
    if (sunctx_) SUNContext_Free(&sunctx_);
  }

  std::string name() const override { return adaptive_ ? "arkode" : "arkode-fixed"; }
  int order() const override { return table_.order; }

  void start(OdeSystem& system, double t0, double* y) override {
    sys_ = &system;
    t_ = t0;
    callbacks_ = ArkodeCallbackState{.sys = &system, .t_last_accepted = t0};
    y_ = wrap(y);
    resizable_ = system.mayResize();
    mem_ = ERKStepCreate(&ArkodeErk::rhs, t0, y_, sunctx_);
    if (!mem_) throw std::runtime_error("ERKStepCreate failed");
    checkArkode(ERKStepSetUserData(mem_, this), "SetUserData");
    checkArkode(ERKStepSetTableNum(mem_, static_cast<ARKODE_ERKTableID>(table_.id)), "SetTableNum");
    checkArkode(ERKStepSetMaxNumSteps(mem_, 1000000000L), "SetMaxNumSteps");
    checkArkode(ERKStepSetPostprocessStepFn(mem_, &ArkodeErk::postStep), "SetPostprocessStepFn");
    if (std::isfinite(control_.max_step)) checkArkode(ERKStepSetMaxStep(mem_, control_.max_step), "SetMaxStep");
    if (adaptive_) {
      setTolerances();
      checkArkode(ERKStepSetStabilityFn(mem_, &ArkodeErk::stability, this), "SetStabilityFn");
      // The limits carry their coefficients already (arkodeStabilityStep, sundials_support.hpp).
      checkArkode(ERKStepSetCFLFraction(mem_, kArkodeCflFraction), "SetCFLFraction");
      // ARKODE keeps the step unchanged while the proposed one is within [1, 1.5] times it;
      // that window froze steps below the stability limit after the start-up ramp (up to 28 %
      // more steps, docs/studies.md). Let every proposal through.
      checkArkode(ERKStepSetFixedStepBounds(mem_, 1.0, 1.0), "SetFixedStepBounds");
      if (initial_step_ > 0) checkArkode(ERKStepSetInitStep(mem_, initial_step_), "SetInitStep");
    }
  }

  bool advance(double tout) override {
    checkArkode(ERKStepSetStopTime(mem_, tout), "SetStopTime");
    // A state whose length may change is advanced one step at a time, so that the particle
    // changes happen between steps, outside ERKStepEvolve.
    const int mode = adaptive_ && !resizable_ ? ARK_NORMAL : ARK_ONE_STEP;
    while (t_ < tout) {
      if (!adaptive_) {
        double h = control_.fixed_step > 0 ? control_.fixed_step : limit();
        if (!std::isfinite(h))
          throw InputError("integrator: no stability limit bounds the time step; set integrator.max_step or integrator.step (s)");
        checkArkode(ERKStepSetFixedStep(mem_, h), "SetFixedStep");
      }
      double t = t_;
      const int flag = ERKStepEvolve(mem_, tout, y_, &t, mode);
      t_ = t;
      if (callbacks_.stop_requested) return false;
      if (!callbacks_.pending_error.empty()) throw NumericalFailure(callbacks_.pending_error);
      if (flag < 0) {
        std::ostringstream os;
        os << "ARKODE " << name() << " (" << table_.name << ") failed at t = " << t_ << " s: " << arkodeFlagName(flag);
        if (flag == ARK_ERR_FAILURE || flag == ARK_TOO_CLOSE)
          os << " (the error test failed repeatedly or the step became too small: the solution is blowing up or the tolerances are too tight)";
        // Every process's ARKODE decides from the same global norms (a distributed state).
        throw SharedNumericalFailure(os.str());
      }
      if (flag == ARK_TSTOP_RETURN) t_ = tout;
      if (resizable_ && sys_->resizePending()) resize(tout);
    }
    return true;
  }

  double time() const override { return t_; }
  double lastStep() const override {
    double h = 0;
    if (mem_) ERKStepGetLastStep(mem_, &h);
    return h;
  }
  IntegratorStats stats() const override {
    IntegratorStats s;
    if (!mem_) return s;
    long steps = 0, attempts = 0, nfe = 0;
    ERKStepGetNumSteps(mem_, &steps);
    ERKStepGetNumStepAttempts(mem_, &attempts);
    ERKStepGetNumRhsEvals(mem_, &nfe);
    s.steps = static_cast<std::uint64_t>(steps);
    s.rejected_steps = static_cast<std::uint64_t>(attempts - steps);
    s.rhs_evals = static_cast<std::uint64_t>(nfe);
    return s;
  }

  StepLimits limits() const override { return sys_ ? stepLimits(sys_->stability(), control_) : StepLimits{}; }

 private:
  double limit() const { return stepLimits(sys_->stability(), control_).smallest(); }

  // N_Vector over the system's state buffer (no copy): the OpenMP vector with fused operations
  // for large states when threads are available.
  N_Vector wrap(double* y) { return wrapState(y, sys_->size(), sunctx_, sys_->stateCommunicator()); }

  // Per-field absolute tolerances (vector abstol) over the state segments.
  void setTolerances() {
    if (atol_) N_VDestroy(atol_);
    atol_ = N_VClone(y_);
    fillTolerances(N_VGetArrayPointer(atol_), sys_->size(), sys_->segments(), atol_segments_);
    checkArkode(ERKStepSVtolerances(mem_, rtol_, atol_), "SVtolerances");
  }

  // The particle set changed after the step just accepted: the system rewrites the state,
  // ERKStepResize takes the new vector (hscale 1: the step size goes on; without a resize
  // function ARKODE clones its work vectors from it), the tolerances are set again (ARKODE
  // requires it after a resize with vector abstol) and so is the stop time.
  void resize(double tout) {
    double* y = sys_->resizeState(t_, N_VGetArrayPointer(y_));
    N_Vector fresh = wrap(y);
    checkArkode(ERKStepResize(mem_, fresh, 1.0, t_, nullptr, nullptr), "Resize");
    destroyState(y_);
    y_ = fresh;
    if (adaptive_) setTolerances();
    checkArkode(ERKStepSetStopTime(mem_, tout), "SetStopTime");
  }

  // A right-hand side must not throw through C code: failures are kept and reported after
  // ERKStepEvolve returns (a negative return is unrecoverable for ERKStep).
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* data) {
    auto* self = static_cast<ArkodeErk*>(data);
    return self->callbacks_.guarded([&] { self->sys_->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)); });
  }

  static int postStep(realtype t, N_Vector y, void* data) {
    return static_cast<ArkodeErk*>(data)->callbacks_.afterStep(t, N_VGetArrayPointer(y));
  }

  static int stability(N_Vector, realtype, realtype* hstab, void* data) {
    *hstab = arkodeStabilityStep(static_cast<ArkodeErk*>(data)->limit());
    return 0;
  }

  bool adaptive_;
  ButcherTableInfo table_;
  StepControl control_;
  double rtol_;
  std::vector<double> atol_segments_;  // position, density, velocity, evolving fields (stress)
  double initial_step_;
  SUNContext sunctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector y_ = nullptr, atol_ = nullptr;
  OdeSystem* sys_ = nullptr;
  double t_ = 0;
  bool resizable_ = false;
  ArkodeCallbackState callbacks_;
};

const ButcherTableInfo& tableFromConfig(ConfigTable& cfg, bool adaptive) {
  std::vector<std::string> names;
  for (const auto& t : erkTables())
    if (!adaptive || t.embedding_order > 0) names.push_back(t.name);
  const std::string name = cfg.choice("table", std::string("DORMAND_PRINCE_7_4_5"), names);
  for (const auto& t : erkTables())
    if (t.name == name) return t;
  cfg.fail("table", "a known table");
}

}  // namespace

std::unique_ptr<Integrator> makeArkode(ConfigTable& cfg, const StepControl& c, const ReferenceScales& s) {
  const ButcherTableInfo& table = tableFromConfig(cfg, true);
  const ErrorTolerances tol = readTolerances(cfg, s);
  const double h0 = cfg.optionalNumber("initial_step", Bound::positive, "s").value_or(0.0);
  return std::make_unique<ArkodeErk>(true, table, c, tol.rtol, tol.atol_by_segment, h0);
}

std::unique_ptr<Integrator> makeArkodeFixed(ConfigTable& cfg, const StepControl& c, const ReferenceScales&) {
  const ButcherTableInfo& table = tableFromConfig(cfg, false);
  return std::make_unique<ArkodeErk>(false, table, c, 0.0, std::vector<double>{0, 0, 0, 0}, 0.0);
}

}  // namespace vesph
