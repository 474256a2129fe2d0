// SUNDIALS ARKODE ARKStep implicit-explicit (IMEX) additive Runge-Kutta integrators
// (SUNDIALS 6.4.1; docs/theory.md "Implicit-explicit integration").
//
//   arkode-imex        adaptive, error-controlled ARK pair (an explicit and a diagonally
//                      implicit table, integrator.table); the step is bounded by the stability
//                      limits of the explicit part only (OdeSystem::explicitStability: no
//                      viscous or relaxation limit when those terms are implicit).
//   arkode-imex-fixed  the same pairs in fixed-step mode, the step from the explicit part's
//                      limits (recomputed every step) or integrator.step.
//
// The right-hand side splits as f = f_E + f_I (OdeSystem::rhsPart): each effect declares its
// implicit term (the viscous force, the linear relaxation -S/lambda of Oldroyd-B/UCM). f_I is
// linear in the velocities and evolving stresses at given positions and densities, and has no
// position or density rates. Each implicit stage solves z - gamma f_I(z) = a by Newton's method
// with a matrix-free GMRES (SUNLinSol_SPGMR). The Jacobian-vector product is exact by
// linearity: J w = (f_I(y + sigma w_v) - f_I(y)) / sigma with only the velocity and stress
// components perturbed, so the positions and densities are frozen in it (their columns of the
// Jacobian are dropped). GMRES is preconditioned (right) by the diagonal of I - gamma J
// (rhsPart implicit_diagonal: the viscous sum -sum_j w_ij, the relaxation -1/lambda), set up
// when ARKODE asks for it. The first Newton iteration therefore sets the stage positions
// exactly (their rows are the identity) and the second solves the velocities at those
// positions; the convergence test, not ARKStepSetLinear's single iteration, ends it (one
// iteration would leave an error proportional to the predictor's position error).
//
// As for ERKStep (src/time/arkode.cpp): the state buffer is wrapped without copy, output
// times are reached with a stop time, afterStep runs in the post-process function, and a
// state whose length may change is advanced one step at a time (ARKStepResize, and a new
// linear solver for the new length).
#include <arkode/arkode_arkstep.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spgmr.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sundials_support.hpp"
#include "vesph/core/types.hpp"
#include "vesph/time/integrator_factory.hpp"

namespace vesph {

const std::vector<ArkPairInfo>& arkPairs() {
  static const std::vector<ArkPairInfo> pairs = [] {
    // The additive pairs of SUNDIALS 6.4.1 (ARKStepSetTableName; Kennedy & Carpenter 2003,
    // 2019): explicit and implicit tables of the same name.
    const char* names[][3] = {{"ARK324L2SA", "ARK324L2SA_ERK_4_2_3", "ARK324L2SA_DIRK_4_2_3"},
                              {"ARK436L2SA", "ARK436L2SA_ERK_6_3_4", "ARK436L2SA_DIRK_6_3_4"},
                              {"ARK437L2SA", "ARK437L2SA_ERK_7_3_4", "ARK437L2SA_DIRK_7_3_4"},
                              {"ARK548L2SA", "ARK548L2SA_ERK_8_4_5", "ARK548L2SA_DIRK_8_4_5"},
                              {"ARK548L2SAb", "ARK548L2SAb_ERK_8_4_5", "ARK548L2SAb_DIRK_8_4_5"}};
    std::vector<ArkPairInfo> out;
    for (const auto& n : names) {
      ARKodeButcherTable E = ARKodeButcherTable_LoadERKByName((std::string("ARKODE_") + n[1]).c_str());
      ARKodeButcherTable I = ARKodeButcherTable_LoadDIRKByName((std::string("ARKODE_") + n[2]).c_str());
      if (!E || !I || E->stages != I->stages || E->q != I->q)
        throw std::logic_error(std::string("SUNDIALS ARK pair mismatch for ") + n[0]);
      out.push_back({n[0], n[1], n[2], E->q, E->p, E->stages});
      ARKodeButcherTable_Free(E);
      ARKodeButcherTable_Free(I);
    }
    return out;
  }();
  return pairs;
}

namespace {

// Krylov subspace of GMRES (no restarts): with the diagonal preconditioner the viscous operator
// at 20-100x the explicit limit converges in a few iterations.
constexpr int kKrylovDimension = 20;

class ArkodeImex final : public Integrator {
 public:
  ArkodeImex(bool adaptive, const ArkPairInfo& pair, const StepControl& control, ErrorTolerances tolerances,
             double initial_step)
      : adaptive_(adaptive), pair_(pair), control_(control), tol_(std::move(tolerances)), initial_step_(initial_step) {
    if (SUNContext_Create(nullptr, &sunctx_) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~ArkodeImex() override {
    if (mem_) ARKStepFree(&mem_);
    if (linear_solver_) SUNLinSolFree(linear_solver_);
    if (y_) N_VDestroy(y_);
    if (atol_) N_VDestroy(atol_);
    if (sunctx_) SUNContext_Free(&sunctx_);
  }

  std::string name() const override { return adaptive_ ? "arkode-imex" : "arkode-imex-fixed"; }
  int order() const override { return pair_.order; }

  void start(OdeSystem& system, double t0, double* y) override {
    sys_ = &system;
    t_ = t0;
    callbacks_ = ArkodeCallbackState{.sys = &system, .t_last_accepted = t0};
    y_ = wrapState(y, sys_->size(), sunctx_);
    resizable_ = system.mayResize();
    mem_ = ARKStepCreate(&ArkodeImex::explicitRhs, &ArkodeImex::implicitRhs, t0, y_, sunctx_);
    if (!mem_) throw std::runtime_error("ARKStepCreate failed");
    checkArkode(ARKStepSetUserData(mem_, this), "SetUserData");
    checkArkode(ARKStepSetTableName(mem_, ("ARKODE_" + pair_.implicit_table).c_str(), ("ARKODE_" + pair_.explicit_table).c_str()),
          "SetTableName");
    checkArkode(ARKStepSetMaxNumSteps(mem_, 1000000000L), "SetMaxNumSteps");
    checkArkode(ARKStepSetPostprocessStepFn(mem_, &ArkodeImex::postStep), "SetPostprocessStepFn");
    if (std::isfinite(control_.max_step)) checkArkode(ARKStepSetMaxStep(mem_, control_.max_step), "SetMaxStep");
    // The tolerances set the error control (adaptive) and the Newton and Krylov stopping
    // tests (both modes).
    setTolerances();
    attachLinearSolver();
    if (adaptive_) {
      checkArkode(ARKStepSetStabilityFn(mem_, &ArkodeImex::stability, this), "SetStabilityFn");
      // As for ERKStep (src/time/arkode.cpp): the limits carry their coefficients already,
      // and every proposed step goes through.
      checkArkode(ARKStepSetCFLFraction(mem_, kArkodeCflFraction), "SetCFLFraction");
      checkArkode(ARKStepSetFixedStepBounds(mem_, 1.0, 1.0), "SetFixedStepBounds");
      if (initial_step_ > 0) checkArkode(ARKStepSetInitStep(mem_, initial_step_), "SetInitStep");
    }
  }

  bool advance(double tout) override {
    checkArkode(ARKStepSetStopTime(mem_, tout), "SetStopTime");
    const int mode = adaptive_ && !resizable_ ? ARK_NORMAL : ARK_ONE_STEP;
    while (t_ < tout) {
      if (!adaptive_) {
        double h = control_.fixed_step > 0 ? control_.fixed_step : limits().smallest();
        if (!std::isfinite(h))
          throw InputError("integrator: no stability limit bounds the time step; set integrator.max_step or integrator.step (s)");
        checkArkode(ARKStepSetFixedStep(mem_, h), "SetFixedStep");
      }
      double t = t_;
      const int flag = ARKStepEvolve(mem_, tout, y_, &t, mode);
      t_ = t;
      if (callbacks_.stop_requested) return false;
      if (!callbacks_.pending_error.empty()) throw NumericalFailure(callbacks_.pending_error);
      if (flag < 0) {
        std::ostringstream os;
        os << "ARKODE " << name() << " (" << pair_.name << ") failed at t = " << t_ << " s: " << arkodeFlagName(flag);
        if (flag == ARK_ERR_FAILURE || flag == ARK_TOO_CLOSE)
          os << " (the error test failed repeatedly or the step became too small: the solution is blowing up or the tolerances are too tight)";
        if (flag == ARK_CONV_FAILURE || flag == ARK_LSOLVE_FAIL)
          os << " (the implicit stage solve did not converge: try a smaller integrator.max_step)";
        throw NumericalFailure(os.str());
      }
      if (flag == ARK_TSTOP_RETURN) t_ = tout;
      if (resizable_ && sys_->resizePending()) resize(tout);
    }
    return true;
  }

  double time() const override { return t_; }
  double lastStep() const override {
    double h = 0;
    if (mem_) ARKStepGetLastStep(mem_, &h);
    return h;
  }
  // rhs_evals counts the explicit and implicit evaluations, those of the Jacobian-vector
  // products included (each one implicit evaluation).
  IntegratorStats stats() const override {
    IntegratorStats s;
    if (!mem_) return s;
    long steps = 0, attempts = 0, nfe = 0, nfi = 0;
    ARKStepGetNumSteps(mem_, &steps);
    ARKStepGetNumStepAttempts(mem_, &attempts);
    ARKStepGetNumRhsEvals(mem_, &nfe, &nfi);
    s.steps = static_cast<std::uint64_t>(steps);
    s.rejected_steps = static_cast<std::uint64_t>(attempts - steps);
    s.rhs_evals = static_cast<std::uint64_t>(nfe + nfi) + jtimes_evals_;
    return s;
  }

  StepLimits limits() const override { return sys_ ? stepLimits(sys_->explicitStability(), control_) : StepLimits{}; }

 private:
  void setTolerances() {
    if (atol_) N_VDestroy(atol_);
    atol_ = N_VClone(y_);
    fillTolerances(N_VGetArrayPointer(atol_), sys_->size(), sys_->segments(), tol_.atol_by_segment);
    checkArkode(ARKStepSVtolerances(mem_, tol_.rtol, atol_), "SVtolerances");
  }

  // Matrix-free GMRES on the stage systems (I - gamma J) x = b, J w from jtimes.
  void attachLinearSolver() {
    if (linear_solver_) SUNLinSolFree(linear_solver_);
    linear_solver_ = SUNLinSol_SPGMR(y_, SUN_PREC_RIGHT, kKrylovDimension, sunctx_);
    if (!linear_solver_) throw std::runtime_error("SUNLinSol_SPGMR failed");
    checkArkode(ARKStepSetLinearSolver(mem_, linear_solver_, nullptr), "SetLinearSolver");
    checkArkode(ARKStepSetJacTimes(mem_, nullptr, &ArkodeImex::jtimes), "SetJacTimes");
    checkArkode(ARKStepSetPreconditioner(mem_, &ArkodeImex::preconditionerSetup, &ArkodeImex::preconditionerSolve),
          "SetPreconditioner");
    jacobian_diagonal_.assign(sys_->size(), 0.0);
    inverse_preconditioner_.assign(sys_->size(), 1.0);
  }

  void resize(double tout) {
    double* y = sys_->resizeState(t_, N_VGetArrayPointer(y_));
    N_Vector fresh = wrapState(y, sys_->size(), sunctx_);
    checkArkode(ARKStepResize(mem_, fresh, 1.0, t_, nullptr, nullptr), "Resize");
    N_VDestroy(y_);
    y_ = fresh;
    setTolerances();
    attachLinearSolver();  // its work vectors have the old length
    checkArkode(ARKStepSetStopTime(mem_, tout), "SetStopTime");
  }

  // Right-hand sides must not throw through C code: failures are kept and reported after
  // ARKStepEvolve returns.
  int evaluate(RhsPart part, double t, const double* y, double* ydot) {
    return callbacks_.guarded([&] { sys_->rhsPart(part, t, y, ydot); });
  }
  static int explicitRhs(realtype t, N_Vector y, N_Vector ydot, void* data) {
    return static_cast<ArkodeImex*>(data)->evaluate(RhsPart::explicit_part, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  }
  static int implicitRhs(realtype t, N_Vector y, N_Vector ydot, void* data) {
    return static_cast<ArkodeImex*>(data)->evaluate(RhsPart::implicit_part, t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
  }

  // J w for f_I at y, fy = f_I(t, y): f_I is affine in the components from velocity_begin on
  // at frozen positions and densities, so the difference below is exact to round-off for any
  // sigma; sigma scales w to the size of y's values so that the round-off stays relative.
  static int jtimes(N_Vector w, N_Vector Jw, realtype t, N_Vector y, N_Vector fy, void* data, N_Vector tmp) {
    auto* self = static_cast<ArkodeImex*>(data);
    const std::size_t n = self->sys_->size();
    const std::size_t begin = self->sys_->segments().velocity_begin;
    const double* wv = N_VGetArrayPointer(w);
    const double* yv = N_VGetArrayPointer(y);
    double* perturbed = N_VGetArrayPointer(tmp);
    double* out = N_VGetArrayPointer(Jw);
    double w_max = 0, y_max = 0;
    for (std::size_t k = begin; k < n; ++k) {
      w_max = std::max(w_max, std::abs(wv[k]));
      y_max = std::max(y_max, std::abs(yv[k]));
    }
    if (w_max == 0) {
      std::fill(out, out + n, 0.0);
      return 0;
    }
    const double sigma = (y_max > 0 ? y_max : 1.0) / w_max;
    std::copy(yv, yv + begin, perturbed);
    for (std::size_t k = begin; k < n; ++k) perturbed[k] = yv[k] + sigma * wv[k];
    ++self->jtimes_evals_;
    if (const int flag = self->evaluate(RhsPart::implicit_part, t, perturbed, out)) return flag;
    const double* f0 = N_VGetArrayPointer(fy);
    const double inverse_sigma = 1.0 / sigma;
    for (std::size_t k = 0; k < n; ++k) out[k] = (out[k] - f0[k]) * inverse_sigma;
    return 0;
  }

  // The Jacobi preconditioner P = diag(I - gamma J): the diagonal of J at y (recomputed only
  // when ARKODE asks, jok false; the positions change slowly), 1 - gamma J_kk inverted.
  static int preconditionerSetup(realtype t, N_Vector y, N_Vector, booleantype jok, booleantype* jcur, realtype gamma,
                                 void* data) {
    auto* self = static_cast<ArkodeImex*>(data);
    if (!jok) {
      if (const int flag = self->evaluate(RhsPart::implicit_diagonal, t, N_VGetArrayPointer(y), self->jacobian_diagonal_.data()))
        return flag;
      ++self->jtimes_evals_;
      *jcur = SUNTRUE;
    } else {
      *jcur = SUNFALSE;
    }
    const std::size_t n = self->jacobian_diagonal_.size();
    for (std::size_t k = 0; k < n; ++k) {
      const double p = 1.0 - gamma * self->jacobian_diagonal_[k];
      self->inverse_preconditioner_[k] = p > 0 ? 1.0 / p : 1.0;  // J_kk <= 0 for the terms here
    }
    return 0;
  }
  static int preconditionerSolve(realtype, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype, realtype, int,
                                 void* data) {
    auto* self = static_cast<ArkodeImex*>(data);
    const double* rv = N_VGetArrayPointer(r);
    double* zv = N_VGetArrayPointer(z);
    const std::size_t n = self->inverse_preconditioner_.size();
    for (std::size_t k = 0; k < n; ++k) zv[k] = self->inverse_preconditioner_[k] * rv[k];
    return 0;
  }

  static int postStep(realtype t, N_Vector y, void* data) {
    return static_cast<ArkodeImex*>(data)->callbacks_.afterStep(t, N_VGetArrayPointer(y));
  }

  static int stability(N_Vector, realtype, realtype* hstab, void* data) {
    *hstab = arkodeStabilityStep(static_cast<ArkodeImex*>(data)->limits().smallest());
    return 0;
  }

  bool adaptive_;
  ArkPairInfo pair_;
  StepControl control_;
  ErrorTolerances tol_;
  double initial_step_;
  SUNContext sunctx_ = nullptr;
  void* mem_ = nullptr;
  SUNLinearSolver linear_solver_ = nullptr;
  N_Vector y_ = nullptr, atol_ = nullptr;
  OdeSystem* sys_ = nullptr;
  double t_ = 0;
  bool resizable_ = false;
  std::uint64_t jtimes_evals_ = 0;  // implicit evaluations for J w and the preconditioner
  std::vector<double> jacobian_diagonal_, inverse_preconditioner_;
  ArkodeCallbackState callbacks_;
};

// integrator.table: the pair's name (ARK324L2SA) or the name of either of its tables.
const ArkPairInfo& pairFromConfig(ConfigTable& cfg) {
  std::vector<std::string> names;
  for (const auto& p : arkPairs()) names.insert(names.end(), {p.name, p.explicit_table, p.implicit_table});
  const std::string name = cfg.choice("table", std::string("ARK324L2SA"), names);
  for (const auto& p : arkPairs())
    if (name == p.name || name == p.explicit_table || name == p.implicit_table) return p;
  cfg.fail("table", "a known ARK pair");
}

}  // namespace

std::unique_ptr<Integrator> makeArkodeImex(ConfigTable& cfg, const StepControl& c, const ReferenceScales& s) {
  const ArkPairInfo& pair = pairFromConfig(cfg);
  ErrorTolerances tol = readTolerances(cfg, s);
  const double h0 = cfg.optionalNumber("initial_step", Bound::positive, "s").value_or(0.0);
  return std::make_unique<ArkodeImex>(true, pair, c, std::move(tol), h0);
}

std::unique_ptr<Integrator> makeArkodeImexFixed(ConfigTable& cfg, const StepControl& c, const ReferenceScales& s) {
  const ArkPairInfo& pair = pairFromConfig(cfg);
  ErrorTolerances tol = readTolerances(cfg, s);  // for the Newton and Krylov stopping tests
  return std::make_unique<ArkodeImex>(false, pair, c, std::move(tol), 0.0);
}

}  // namespace vesph
