// Fixed-step semi-implicit reference integrator (docs/theory.md §9.6): the same splitting
// f = f_E + f_I as arkode-imex (OdeSystem::rhsPart; the viscous force and the linear part of the
// Oldroyd-B/UCM stress rate in f_I), composed by Strang splitting
//   y^{n+1} = S_I(dt/2) o S_E(dt) o S_I(dt/2) y^n,
// second order when each sub-flow is integrated to second order.
//   S_E: the midpoint rule of Fang et al. (src/time/leapfrog.cpp, theory.md §9.2) on f_E alone,
//        from the rate carried from the previous step's last f_E evaluation. That rate enters
//        the predictor only, where an O(dt) error (the implicit half steps change the
//        velocities between it and the step's start) costs O(dt^3) per step; the leapfrog's
//        trapezoidal density corrector would take the stale continuity rate at full weight and
//        lose an order.
//   S_I: y' = f_I(t, y) over dt/2 by the two-stage, stiffly accurate, L-stable SDIRK method
//        with gamma = 1 - 1/sqrt(2) (Alexander 1977; Hairer & Wanner, Solving ODEs II, IV.6):
//          k1 = f_I(t + gamma tau, y + gamma tau k1)
//          k2 = f_I(t + tau, y + (1 - gamma) tau k1 + gamma tau k2)
//          y <- y + tau ((1 - gamma) k1 + gamma k2),   tau = dt/2.
//        L-stable: its amplification tends to 0 as tau|lambda| grows, so the viscous modes far
//        above the explicit limit are damped, not reflected as with Crank-Nicolson (-1).
//        f_I has no position or density rate, so the positions and densities are constant in S_I
//        and f_I is affine in the remaining values (velocities, evolving stresses): each stage is
//        the linear system (I - gamma tau J) k = f_I(t_i, base_i), J w exact by linearity
//        (the difference quotient of arkode_imex.cpp), solved by restarted GMRES, right-
//        preconditioned with the diagonal of I - gamma tau J (RhsPart::implicit_diagonal), to
//        the relative residual integrator.rtol in a norm that weighs each field (velocities,
//        stresses) by its own scale.
// The step is the explicit part's stability limit (OdeSystem::explicitStability: no viscous
// or relaxation limit for the implicit terms) or integrator.step, as for the other fixed-step
// integrators (fixed_step.hpp, which also carries f_E for checkpoints). Every evaluation of a
// part, of the diagonal and of a product J w counts in stats().rhs_evals.
#include <mpi.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fixed_step.hpp"

namespace vesph {
namespace {

// The SDIRK diagonal gamma = 1 - 1/sqrt(2).
constexpr double kGamma = 0.29289321881345247560;
// Krylov vectors between GMRES restarts (as arkode-imex's dimension).
constexpr int kSemiImplicitKrylovDimension = 20;

class SemiImplicit final : public FixedStepIntegrator {
 public:
  SemiImplicit(const StepControl& c, double linear_rtol, long long max_linear_iterations)
      : FixedStepIntegrator(c, RhsPart::explicit_part),
        linear_rtol_(linear_rtol),
        max_linear_iterations_(max_linear_iterations) {}
  std::string name() const override { return "semi-implicit"; }
  int order() const override { return 2; }

 protected:
  void allocate() override {
    // A run across processes: the state is each process's part; every sum and maximum below is
    // taken over all of them, so that every process makes the same GMRES decisions.
    const void* communicator = sys_->stateCommunicator();
    comm_ = communicator ? *static_cast<const MPI_Comm*>(communicator) : MPI_COMM_NULL;
    const StateSegments s = sys_->segments();
    implicit_begin_ = s.velocity_begin;
    m_ = n_ - implicit_begin_;
    velocity_count_ = s.velocity_end - s.velocity_begin;
    base_.assign(n_, 0.0);
    probe_.assign(n_, 0.0);
    implicit_rate_.assign(n_, 0.0);
    diagonal_.assign(n_, 0.0);
    for (auto* v : {&b_, &k1_, &k2_, &x_, &z_, &w_, &weight_, &inverse_preconditioner_}) v->assign(m_, 0.0);
    krylov_.assign(static_cast<std::size_t>(kSemiImplicitKrylovDimension + 1) * m_, 0.0);
    partial_sums_.assign(static_cast<std::size_t>(omp_get_max_threads()), 0.0);
    diagonal_valid_ = false;
  }

  void step(double dt) override {
    // J's diagonal depends on the positions and densities only, which S_I leaves alone: the
    // one of the last half step (at the step's end) serves the next step's first half step,
    // unless a hook changed the state since or the buffers are new (start, resize).
    if (!diagonal_valid_ || sys_->afterStepChangesState()) refreshDiagonal(t_);
    implicitHalfStep(t_, 0.5 * dt);
    midpointStep(dt);  // S_E(dt) on the carried f_E
    refreshDiagonal(t_ + dt);
    implicitHalfStep(t_ + 0.5 * dt, 0.5 * dt);
  }

 private:
  void evaluatePart(RhsPart part, double t, const double* y, double* f) {
    sys_->rhsPart(part, t, y, f);
    ++stats_.rhs_evals;
  }

  void refreshDiagonal(double t) {
    if (m_ == 0 && comm_ == MPI_COMM_NULL) return;  // across processes every process evaluates (collective)
    evaluatePart(RhsPart::implicit_diagonal, t, y_, diagonal_.data());
    diagonal_valid_ = true;
  }

  // S_I(tau) from time t on y_ (in place).
  void implicitHalfStep(double t, double tau) {
    if (m_ == 0 && comm_ == MPI_COMM_NULL) return;
    const std::size_t begin = implicit_begin_;
    const double gamma_tau = kGamma * tau;
    // Jacobi: diag(I - gamma tau J)^{-1}; J_kk <= 0 for the implicit terms.
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < m_; ++k) {
      const double p = 1.0 - gamma_tau * diagonal_[begin + k];
      inverse_preconditioner_[k] = p > 0 ? 1.0 / p : 1.0;
    }
    // Stage 1 from y.
    std::copy(y_, y_ + n_, base_.begin());
    solveStage(t + gamma_tau, tau, gamma_tau, k1_);
    // Stage 2 from y + (1 - gamma) tau k1.
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < m_; ++k) base_[begin + k] = y_[begin + k] + (1.0 - kGamma) * tau * k1_[k];
    solveStage(t + tau, tau, gamma_tau, k2_);
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t k = 0; k < m_; ++k) y_[begin + k] += tau * ((1.0 - kGamma) * k1_[k] + kGamma * k2_[k]);
  }

  // Solves (I - gamma_tau J) k = f_I(t, base) for k, J the Jacobian of f_I in the implicit
  // values at base_'s positions and densities.
  void solveStage(double t, double tau, double gamma_tau, std::vector<double>& k) {
    const std::size_t begin = implicit_begin_;
    evaluatePart(RhsPart::implicit_part, t, base_.data(), implicit_rate_.data());
    std::copy(implicit_rate_.begin() + static_cast<std::ptrdiff_t>(begin), implicit_rate_.end(), b_.begin());
    std::copy(base_.begin(), base_.begin() + static_cast<std::ptrdiff_t>(begin), probe_.begin());
    // The perturbation scale of J w (as arkode_imex.cpp's jtimes): w scaled to the size of the
    // base values, so that the difference quotient's round-off stays relative.
    base_max_ = 0;
#pragma omp parallel for reduction(max : base_max_) schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t i = 0; i < m_; ++i) base_max_ = std::max(base_max_, std::abs(base_[begin + i]));
    base_max_ = globalMax(base_max_);
    setWeights(tau);
    gmres(t, gamma_tau, k);
  }

  // Per field (velocities; evolving stresses) the scale of a rate: |base|/tau + |f_I|, its
  // largest value; a field at rest with no rate takes the largest scale of the others.
  void setWeights(double tau) {
    const std::size_t begin = implicit_begin_;
    const std::size_t bounds[] = {0, std::min(velocity_count_, m_), m_};
    double scale[2] = {0, 0};
    for (int s = 0; s < 2; ++s)
      for (std::size_t i = bounds[s]; i < bounds[s + 1]; ++i)
        scale[s] = std::max(scale[s], std::abs(base_[begin + i]) / tau + std::abs(b_[i]));
    if (comm_ != MPI_COMM_NULL) MPI_Allreduce(MPI_IN_PLACE, scale, 2, MPI_DOUBLE, MPI_MAX, comm_);
    const double largest = std::max(scale[0], scale[1]);
    for (int s = 0; s < 2; ++s) {
      const double w = 1.0 / (scale[s] > 0 ? scale[s] : (largest > 0 ? largest : 1.0));
      for (std::size_t i = bounds[s]; i < bounds[s + 1]; ++i) weight_[i] = w;
    }
  }

  // out = (I - gamma_tau J) u for an unscaled u; one evaluation of f_I.
  void applyOperator(double t, double gamma_tau, const double* u, double* out) {
    const std::size_t begin = implicit_begin_;
    double u_max = 0;
#pragma omp parallel for reduction(max : u_max) schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t i = 0; i < m_; ++i) u_max = std::max(u_max, std::abs(u[i]));
    u_max = globalMax(u_max);
    if (u_max == 0) {
      std::fill(out, out + m_, 0.0);
      return;
    }
    const double sigma = (base_max_ > 0 ? base_max_ : 1.0) / u_max;
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t i = 0; i < m_; ++i) probe_[begin + i] = base_[begin + i] + sigma * u[i];
    evaluatePart(RhsPart::implicit_part, t, probe_.data(), implicit_rate_.data());
    const double* f = implicit_rate_.data() + begin;
    const double factor = gamma_tau / sigma;
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t i = 0; i < m_; ++i) out[i] = u[i] - factor * (f[i] - b_[i]);
  }

  // Dot product with a fixed partition per thread count, summed in order: the same result
  // from run to run (an OpenMP reduction may combine in any order).
  double dot(const double* a, const double* b) { return globalSum(localDot(a, b)); }
  double localDot(const double* a, const double* b) {
    if (m_ < kParallelMinimumValues) {
      double s = 0;
      for (std::size_t i = 0; i < m_; ++i) s += a[i] * b[i];
      return s;
    }
    std::size_t threads = 1;
#pragma omp parallel
    {
      const std::size_t nt = static_cast<std::size_t>(omp_get_num_threads());
      const std::size_t id = static_cast<std::size_t>(omp_get_thread_num());
      if (id == 0) threads = nt;
      double s = 0;
      for (std::size_t i = m_ * id / nt, e = m_ * (id + 1) / nt; i < e; ++i) s += a[i] * b[i];
      partial_sums_[id] = s;
    }
    double s = 0;
    for (std::size_t i = 0; i < threads; ++i) s += partial_sums_[i];
    return s;
  }

  // Restarted GMRES(kSemiImplicitKrylovDimension) for (I - gamma_tau J) k = b_ from k = 0, right-
  // preconditioned by inverse_preconditioner_, in the inner product weighted by weight_
  // (Saad 2003, Iterative Methods for Sparse Linear Systems: §6.5, Givens rotations; §9.3,
  // right preconditioning). Stops when the weighted residual is at most linear_rtol_ times the
  // weighted b. Starting from the previous stage's rate instead of zero was measured to cost
  // more products (docs/studies.md §6).
  void gmres(double t, double gamma_tau, std::vector<double>& k) {
    constexpr int M = kSemiImplicitKrylovDimension;
    std::fill(k.begin(), k.end(), 0.0);
    double* r = w_.data();
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
    for (std::size_t i = 0; i < m_; ++i) r[i] = weight_[i] * b_[i];
    double beta = std::sqrt(dot(r, r));
    if (!std::isfinite(beta)) fail(t, "the implicit part is not finite");
    if (beta == 0) return;
    const double b_norm = beta;
    const double target = linear_rtol_ * b_norm;
    long long iterations = 0;
    double h[M + 1][M] = {}, cs[M] = {}, sn[M] = {}, g[M + 1] = {}, coefficients[M] = {};
    while (true) {
      double* v0 = krylov_.data();
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
      for (std::size_t i = 0; i < m_; ++i) v0[i] = r[i] / beta;
      std::fill(std::begin(g), std::end(g), 0.0);
      g[0] = beta;
      int used = 0;
      double residual = beta;
      for (int j = 0; j < M; ++j) {
        const double* vj = krylov_.data() + static_cast<std::size_t>(j) * m_;
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
        for (std::size_t i = 0; i < m_; ++i) z_[i] = inverse_preconditioner_[i] * vj[i] / weight_[i];
        applyOperator(t, gamma_tau, z_.data(), x_.data());
        double* w = w_.data();
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
        for (std::size_t i = 0; i < m_; ++i) w[i] = weight_[i] * x_[i];
        for (int i = 0; i <= j; ++i) {  // modified Gram-Schmidt
          const double* vi = krylov_.data() + static_cast<std::size_t>(i) * m_;
          h[i][j] = dot(w, vi);
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
          for (std::size_t q = 0; q < m_; ++q) w[q] -= h[i][j] * vi[q];
        }
        h[j + 1][j] = std::sqrt(dot(w, w));
        const double subdiagonal = h[j + 1][j];
        if (subdiagonal > 0) {
          double* next = krylov_.data() + static_cast<std::size_t>(j + 1) * m_;
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
          for (std::size_t q = 0; q < m_; ++q) next[q] = w[q] / subdiagonal;
        }
        for (int i = 0; i < j; ++i) {  // previous rotations on the new column
          const double a = h[i][j], bb = h[i + 1][j];
          h[i][j] = cs[i] * a + sn[i] * bb;
          h[i + 1][j] = -sn[i] * a + cs[i] * bb;
        }
        const double a = h[j][j], bb = h[j + 1][j], norm = std::hypot(a, bb);
        cs[j] = norm > 0 ? a / norm : 1.0;
        sn[j] = norm > 0 ? bb / norm : 0.0;
        h[j][j] = norm;
        h[j + 1][j] = 0;
        g[j + 1] = -sn[j] * g[j];
        g[j] = cs[j] * g[j];
        residual = std::abs(g[j + 1]);
        ++iterations;
        used = j + 1;
        if (!std::isfinite(residual)) fail(t, "the Krylov iteration is not finite");
        if (residual <= target || subdiagonal == 0 || iterations >= max_linear_iterations_) break;
      }
      // k += P^{-1} W^{-1} V c, H c = g (upper triangular).
      for (int i = used - 1; i >= 0; --i) {
        double s = g[i];
        for (int q = i + 1; q < used; ++q) s -= h[i][q] * coefficients[q];
        coefficients[i] = h[i][i] != 0 ? s / h[i][i] : 0.0;
      }
      std::fill(z_.begin(), z_.end(), 0.0);
      for (int i = 0; i < used; ++i) {
        const double* vi = krylov_.data() + static_cast<std::size_t>(i) * m_;
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
        for (std::size_t q = 0; q < m_; ++q) z_[q] += coefficients[i] * vi[q];
      }
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
      for (std::size_t q = 0; q < m_; ++q) k[q] += inverse_preconditioner_[q] * z_[q] / weight_[q];
      if (residual <= target) return;
      // Restart from the true residual (also after a breakdown that did not converge).
      applyOperator(t, gamma_tau, k.data(), x_.data());
#pragma omp parallel for schedule(static) if (m_ >= kParallelMinimumValues)
      for (std::size_t i = 0; i < m_; ++i) r[i] = weight_[i] * (b_[i] - x_[i]);
      beta = std::sqrt(dot(r, r));
      if (beta <= target) return;
      if (!std::isfinite(beta)) fail(t, "the implicit part is not finite");
      if (iterations >= max_linear_iterations_) {
        std::ostringstream os;
        os << "the implicit stage solve did not converge in " << iterations
           << " GMRES iterations (integrator.max_linear_iterations): relative residual " << beta / b_norm
           << " > integrator.rtol = " << linear_rtol_ << "; take a smaller step (integrator.step, max_step)";
        fail(t, os.str());
      }
    }
  }

  double globalSum(double local) const {
    if (comm_ != MPI_COMM_NULL) MPI_Allreduce(MPI_IN_PLACE, &local, 1, MPI_DOUBLE, MPI_SUM, comm_);
    return local;
  }
  double globalMax(double local) const {
    if (comm_ != MPI_COMM_NULL) MPI_Allreduce(MPI_IN_PLACE, &local, 1, MPI_DOUBLE, MPI_MAX, comm_);
    return local;
  }
  // The stage solves' failures come from global values: every process meets them together.
  [[noreturn]] void fail(double t, const std::string& what) const {
    if (comm_ != MPI_COMM_NULL) throw SharedNumericalFailure(failure(t, what));
    throw NumericalFailure(failure(t, what));
  }

  std::string failure(double t, const std::string& what) const {
    std::ostringstream os;
    os << "semi-implicit: at t = " << t << " s: " << what;
    return os.str();
  }

  double linear_rtol_;
  long long max_linear_iterations_;
  std::size_t implicit_begin_ = 0, m_ = 0, velocity_count_ = 0;
  double base_max_ = 0;
  bool diagonal_valid_ = false;
  MPI_Comm comm_ = MPI_COMM_NULL;  // the state's processes (a run across processes)
  // Full-length: the stage's base state, the probe state of J w, f_I's output, J's diagonal.
  std::vector<double> base_, probe_, implicit_rate_, diagonal_;
  // Implicit-length (from velocity_begin on): the stage right-hand side f_I(base), the stage
  // rates, GMRES work vectors, the field weights, the Jacobi preconditioner.
  std::vector<double> b_, k1_, k2_, x_, z_, w_, weight_, inverse_preconditioner_;
  std::vector<double> krylov_;  // (kSemiImplicitKrylovDimension + 1) basis vectors of the implicit length
  std::vector<double> partial_sums_;
};

}  // namespace

// integrator.rtol: the relative residual of the stage solves (default 1e-8, so that the
// reference's solve error stays far below its truncation error); integrator.
// max_linear_iterations: GMRES iterations per stage solve before a numerical failure.
std::unique_ptr<Integrator> makeSemiImplicit(ConfigTable& cfg, const StepControl& c, const ReferenceScales&) {
  const double rtol = cfg.numberIn("rtol", 1e-8, 1e-14, 0.5);
  const long long max_iterations = cfg.integer("max_linear_iterations", 500, 1, 1000000);
  return std::make_unique<SemiImplicit>(c, rtol, max_iterations);
}

}  // namespace vesph
