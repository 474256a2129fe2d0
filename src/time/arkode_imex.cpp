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
// position or density rates. Each implicit stage solves z - gamma f_I(z) = a: its position and
// density rows are a's (stageSolve sets them before Newton's iteration starts), and at those
// positions the rest is linear, so one Newton iteration (ARKStepSetLinear) with a GMRES solve
// (SUNLinSol_SPGMR, matrix-free) is the stage's solution, and the stage's implicit rate is
// deduced from it (ARKStepSetDeduceImplicitRhs) instead of evaluated again. The
// Jacobian-vector product is exact by linearity: J w = (f_I(y + sigma w_v) - f_I(y)) / sigma
// with only the velocity and stress components perturbed. GMRES is preconditioned (right) by
// integrator.preconditioner: "amg" (default) one BoomerAMG V-cycle per velocity component on
// the assembled I - gamma L, L the viscous coupling (OdeSystem::implicitVelocityOperator), and
// Jacobi on the other rows; "diagonal" Jacobi on all rows (rhsPart implicit_diagonal: the
// viscous sum -sum_j w_ij, the relaxation -1/lambda). Both are set up when ARKODE asks.
//
// As for ERKStep (src/time/arkode.cpp): the state buffer is wrapped without copy, output
// times are reached with a stop time, afterStep runs in the post-process function, and a
// state whose length may change is advanced one step at a time (ARKStepResize, and a new
// linear solver for the new length).
#include <arkode/arkode_arkstep.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sundials_support.hpp"
#include "vesph/core/types.hpp"
#include "vesph/isph/amg_preconditioner.hpp"
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
constexpr int kImexKrylovDimension = 20;

// integrator.preconditioner: how GMRES on the stage systems is preconditioned.
enum class StagePreconditioner { diagonal, amg };

class ArkodeImex final : public Integrator {
 public:
  ArkodeImex(bool adaptive, const ArkPairInfo& pair, const StepControl& control, ErrorTolerances tolerances,
             double initial_step, StagePreconditioner preconditioner)
      : adaptive_(adaptive), pair_(pair), control_(control), tol_(std::move(tolerances)), initial_step_(initial_step),
        preconditioner_(preconditioner) {
    if (SUNContext_Create(nullptr, &sunctx_) != 0) throw std::runtime_error("SUNContext_Create failed");
  }
  ~ArkodeImex() override {
    if (mem_) ARKStepFree(&mem_);
    if (linear_solver_) SUNLinSolFree(linear_solver_);
    if (nonlinear_solver_) SUNNonlinSolFree(nonlinear_solver_);
    destroyState(y_);
    if (atol_) N_VDestroy(atol_);
    if (sunctx_) SUNContext_Free(&sunctx_);
  }

  std::string name() const override { return adaptive_ ? "arkode-imex" : "arkode-imex-fixed"; }
  int order() const override { return pair_.order; }

  void start(OdeSystem& system, double t0, double* y) override {
    sys_ = &system;
    t_ = t0;
    callbacks_ = ArkodeCallbackState{.sys = &system, .t_last_accepted = t0};
    y_ = wrapState(y, sys_->size(), sunctx_, sys_->stateCommunicator());
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
    attachStageSolver();
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

  // The stage solver: Newton's method with the stage's positions and densities set first
  // (stageSolve), so that one iteration solves the stage (ARKStepSetLinear: f_I is linear in
  // the rest at those positions), and the implicit rates deduced from it instead of evaluated
  // again; matrix-free GMRES on (I - gamma J) x = b, J w from jtimes.
  void attachStageSolver() {
    if (nonlinear_solver_) SUNNonlinSolFree(nonlinear_solver_);
    nonlinear_solver_ = SUNNonlinSol_Newton(y_, sunctx_);
    if (!nonlinear_solver_) throw std::runtime_error("SUNNonlinSol_Newton failed");
    newton_solve_ = nonlinear_solver_->ops->solve;
    nonlinear_solver_->ops->solve = &ArkodeImex::stageSolve;
    checkArkode(ARKStepSetNonlinearSolver(mem_, nonlinear_solver_), "SetNonlinearSolver");
    checkArkode(ARKStepSetLinear(mem_, 0), "SetLinear");
    checkArkode(ARKStepSetDeduceImplicitRhs(mem_, SUNTRUE), "SetDeduceImplicitRhs");
    if (linear_solver_) SUNLinSolFree(linear_solver_);
    linear_solver_ = SUNLinSol_SPGMR(y_, SUN_PREC_RIGHT, kImexKrylovDimension, sunctx_);
    if (!linear_solver_) throw std::runtime_error("SUNLinSol_SPGMR failed");
    checkArkode(ARKStepSetLinearSolver(mem_, linear_solver_, nullptr), "SetLinearSolver");
    checkArkode(ARKStepSetJacTimes(mem_, nullptr, &ArkodeImex::jtimes), "SetJacTimes");
    checkArkode(ARKStepSetPreconditioner(mem_, &ArkodeImex::preconditionerSetup, &ArkodeImex::preconditionerSolve),
          "SetPreconditioner");
    jacobian_diagonal_.assign(sys_->size(), 0.0);
    inverse_preconditioner_.assign(sys_->size(), 1.0);
    have_velocity_operator_ = false;  // set up again at the new length
  }

  void resize(double tout) {
    double* y = sys_->resizeState(t_, N_VGetArrayPointer(y_));
    N_Vector fresh = wrapState(y, sys_->size(), sunctx_, sys_->stateCommunicator());
    checkArkode(ARKStepResize(mem_, fresh, 1.0, t_, nullptr, nullptr), "Resize");
    destroyState(y_);
    y_ = fresh;
    setTolerances();
    attachStageSolver();  // its work vectors have the old length
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
    // Across processes the perturbation must be one and the same everywhere (the implicit part
    // couples each process's values to its neighbours'), and every process must evaluate.
    if (const void* communicator = self->sys_->stateCommunicator()) {
      double maxima[2] = {w_max, y_max};
      MPI_Allreduce(MPI_IN_PLACE, maxima, 2, MPI_DOUBLE, MPI_MAX, *static_cast<const MPI_Comm*>(communicator));
      w_max = maxima[0];
      y_max = maxima[1];
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

  // P approximates I - gamma J. diagonal: the Jacobi preconditioner diag(I - gamma J), the
  // diagonal of J at y, 1 - gamma J_kk inverted. amg: the velocity rows by one BoomerAMG
  // V-cycle per component on the assembled I - gamma L, L the implicit part's scalar velocity
  // coupling (OdeSystem::implicitVelocityOperator: the viscous force's, walls on its
  // diagonal), the other rows (stresses) by Jacobi. J (its diagonal and L) is recomputed only
  // when ARKODE asks (jok false; the positions change slowly); a new gamma rebuilds P from it.
  static int preconditionerSetup(realtype t, N_Vector y, N_Vector, booleantype jok, booleantype* jcur, realtype gamma,
                                 void* data) {
    auto* self = static_cast<ArkodeImex*>(data);
    if (!jok) {
      if (const int flag = self->evaluate(RhsPart::implicit_diagonal, t, N_VGetArrayPointer(y), self->jacobian_diagonal_.data()))
        return flag;
      ++self->jtimes_evals_;
      if (self->preconditioner_ == StagePreconditioner::amg) {
        if (const int flag = self->callbacks_.guarded([&] {
              self->have_velocity_operator_ =
                  self->sys_->implicitVelocityOperator(t, N_VGetArrayPointer(y), self->velocity_operator_);
            }))
          return flag;
      }
      *jcur = SUNTRUE;
    } else {
      *jcur = SUNFALSE;
    }
    const std::size_t n = self->jacobian_diagonal_.size();
    for (std::size_t k = 0; k < n; ++k) {
      const double p = 1.0 - gamma * self->jacobian_diagonal_[k];
      self->inverse_preconditioner_[k] = p > 0 ? 1.0 / p : 1.0;  // J_kk <= 0 for the terms here
    }
    if (self->preconditioner_ == StagePreconditioner::amg && self->have_velocity_operator_)
      return self->callbacks_.guarded([&] { self->setUpVelocityMultigrid(gamma); });
    return 0;
  }
  static int preconditionerSolve(realtype, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype, realtype, int,
                                 void* data) {
    auto* self = static_cast<ArkodeImex*>(data);
    const double* rv = N_VGetArrayPointer(r);
    double* zv = N_VGetArrayPointer(z);
    const std::size_t n = self->inverse_preconditioner_.size();
    for (std::size_t k = 0; k < n; ++k) zv[k] = self->inverse_preconditioner_[k] * rv[k];
    if (self->preconditioner_ == StagePreconditioner::amg && self->have_velocity_operator_)
      return self->callbacks_.guarded([&] { self->applyVelocityMultigrid(rv, zv); });
    return 0;
  }

  // I - gamma L assembled from the kept L, and its hierarchy.
  void setUpVelocityMultigrid(double gamma) {
    const CsrMatrix& L = velocity_operator_;
    stage_matrix_.row_start = L.row_start;
    stage_matrix_.column = L.column;
    stage_matrix_.value.resize(L.value.size());
    const int rows = L.rows();
    for (int i = 0; i < rows; ++i) {
      const int first = L.row_start[static_cast<std::size_t>(i)];
      for (int k = first; k < L.row_start[static_cast<std::size_t>(i) + 1]; ++k)
        stage_matrix_.value[static_cast<std::size_t>(k)] = -gamma * L.value[static_cast<std::size_t>(k)];
      stage_matrix_.value[static_cast<std::size_t>(first)] += 1.0;  // the diagonal is first in each row
    }
    multigrid_.setUp(stage_matrix_);
    component_residual_.resize(static_cast<std::size_t>(rows));
    component_solution_.resize(static_cast<std::size_t>(rows));
  }

  // The velocity rows of z from r: one V-cycle per component (the state holds v_i's D
  // components together).
  void applyVelocityMultigrid(const double* r, double* z) {
    const StateSegments seg = sys_->segments();
    const std::size_t n = seg.velocity_begin - seg.position_end;
    if (n == 0) return;
    const std::size_t dim = seg.position_end / n;
    if (n != static_cast<std::size_t>(velocity_operator_.rows()))
      throw std::logic_error("arkode-imex: the velocity operator's size is not the particle count");
    for (std::size_t a = 0; a < dim; ++a) {
      for (std::size_t i = 0; i < n; ++i) component_residual_[i] = r[seg.velocity_begin + dim * i + a];
      multigrid_.apply(component_residual_.data(), component_solution_.data());
      for (std::size_t i = 0; i < n; ++i) z[seg.velocity_begin + dim * i + a] = component_solution_[i];
    }
  }

  // An implicit stage z = zpred + zcor solves zcor - gamma f_I(z) = sdata (ARKODE's form). f_I
  // has no position or density rate, so those rows of zcor are sdata's: set here, before
  // Newton's first iteration, the stage's positions are exact, f_I is linear in the unknowns
  // left (velocities, stresses) at those positions, and the one iteration of the linear mode is
  // the stage's solution to the Krylov tolerance. (Without it Newton's first iteration ran at
  // the predicted positions and a second, with its own GMRES solve, was needed.)
  static int stageSolve(SUNNonlinearSolver nls, N_Vector y0, N_Vector ycor, N_Vector w, realtype tol,
                        booleantype call_setup, void* arkode_mem) {
    realtype tcur = 0, gamma = 0;
    N_Vector zpred = nullptr, z = nullptr, fi = nullptr, sdata = nullptr;
    void* data = nullptr;
    if (ARKStepGetNonlinearSystemData(arkode_mem, &tcur, &zpred, &z, &fi, &gamma, &sdata, &data) != ARK_SUCCESS)
      return SUN_NLS_MEM_NULL;
    auto* self = static_cast<ArkodeImex*>(data);
    const std::size_t begin = self->sys_->segments().velocity_begin;
    const double* known = N_VGetArrayPointer(sdata);
    double* correction = N_VGetArrayPointer(ycor);
    std::copy(known, known + begin, correction);
    return self->newton_solve_(nls, y0, ycor, w, tol, call_setup, arkode_mem);
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
  SUNNonlinearSolver nonlinear_solver_ = nullptr;
  int (*newton_solve_)(SUNNonlinearSolver, N_Vector, N_Vector, N_Vector, realtype, booleantype, void*) = nullptr;
  N_Vector y_ = nullptr, atol_ = nullptr;
  OdeSystem* sys_ = nullptr;
  double t_ = 0;
  bool resizable_ = false;
  std::uint64_t jtimes_evals_ = 0;  // implicit evaluations for J w and the preconditioner
  std::vector<double> jacobian_diagonal_, inverse_preconditioner_;
  StagePreconditioner preconditioner_;
  bool have_velocity_operator_ = false;
  CsrMatrix velocity_operator_, stage_matrix_;  // L, and I - gamma L
  AmgPreconditioner multigrid_;
  std::vector<double> component_residual_, component_solution_;
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

// integrator.preconditioner (default amg: docs/performance.md measures both).
StagePreconditioner preconditionerFromConfig(ConfigTable& cfg) {
  return cfg.choice("preconditioner", std::string("amg"), {"amg", "diagonal"}) == "amg" ? StagePreconditioner::amg
                                                                                     : StagePreconditioner::diagonal;
}

}  // namespace

std::unique_ptr<Integrator> makeArkodeImex(ConfigTable& cfg, const StepControl& c, const ReferenceScales& s) {
  const ArkPairInfo& pair = pairFromConfig(cfg);
  ErrorTolerances tol = readTolerances(cfg, s);
  const double h0 = cfg.optionalNumber("initial_step", Bound::positive, "s").value_or(0.0);
  return std::make_unique<ArkodeImex>(true, pair, c, std::move(tol), h0, preconditionerFromConfig(cfg));
}

std::unique_ptr<Integrator> makeArkodeImexFixed(ConfigTable& cfg, const StepControl& c, const ReferenceScales& s) {
  const ArkPairInfo& pair = pairFromConfig(cfg);
  ErrorTolerances tol = readTolerances(cfg, s);  // for the Newton and Krylov stopping tests
  return std::make_unique<ArkodeImex>(false, pair, c, std::move(tol), 0.0, preconditionerFromConfig(cfg));
}

}  // namespace vesph
