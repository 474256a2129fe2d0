// Second-order fluid, seed thesis §2.3-2.4 (eqs. 2.2, 2.3, Table 2-1), §4.4.1 (the eight
// forms: Rivlin-Ericksen or CEF with one of four convected derivatives) and §4.4.2 (the four
// discretisation procedures). The algebra is in vesph/physics/constitutive/second_order_fluid.hpp.
//
// The extra stress T = mu A + eps is algebraic in the velocity gradient kappa (computed by
// [effects.velocity_gradient], thesis eq. 3.16 / Fang eq. 23) and DA/Dt: nothing enters the
// ODE state. Procedures (thesis §4.4.2), with what each needs from the scene:
//   1  sigma = -p I + tau + eps, div by eq. 3.18: [effects.pressure_gradient] form "symmetric"
//      and [effects.stress_divergence] over tau + eps; no [effects.viscosity]
//   2  grad p by eq. 3.16 (pressure_gradient form "difference"), div(tau + eps) by eq. 3.18
//      ([effects.stress_divergence]); no [effects.viscosity]
//   3  grad p by 3.16, div tau = mu lap v by eq. 3.37 ([effects.viscosity]), div eps by 3.18
//      ([effects.stress_divergence]); the default
//   4  one step: grad p by 3.16, div T from the first and second derivatives of the velocity
//      (eq. 3.16 and the Hessian eq. 3.36), evaluated in this effect; neither viscosity nor
//      stress_divergence
// This effect writes "elastic_stress" (full D x D, row-major: the mixed derivative makes it
// non-symmetric) for procedures 1-3, the symmetric part of T to "extra_stress" for output, and
// under procedure 4 adds div T / rho to the acceleration itself.
//
// DA/Dt (material_derivative):
//   "lagged"        DA/Dt = G + G^T - kappa kappa - kappa^T kappa^T with G the SPH gradient
//                   (eq. 3.16) of the acceleration of the last accepted step,
//                   a_lag = (v^n - v^(n-1))/(t^n - t^(n-1)) per particle. Within a step the
//                   right-hand side is a function of (t, y) only, under every integrator. First
//                   order in time (the lag is one step); exact in steady flows. Explicit: the
//                   alpha1 term feeds the last step's acceleration back with the factor
//                   |c1| sigma(k)/rho (sigma the symbol of the nested SPH derivative, c1 = alpha1
//                   or alpha1/2), so it is stable only when |c1| sigma_max/rho < 1; setup estimates sigma_max
//                   on the initial lattice and refuses a scene above 1 (docs/theory.md).
//   "quasi_steady"  DA/Dt = 0: the retarded-motion approximation, exact in steady viscometric
//                   flows (the thesis' channel benchmark), no restriction.
#include <cmath>

#include "vesph/physics/constitutive/second_order_fluid.hpp"
#include "vesph/physics/registry.hpp"

namespace vesph {
namespace {

template <int D>
Mat<D> loadRowMajor(const double* p) {
  return Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(p);
}
template <int D>
void storeRowMajor(const Mat<D>& m, double* p) {
  Eigen::Map<Eigen::Matrix<double, D, D, Eigen::RowMajor>> out(p);
  out = m;
}

// Largest symbol over the wave vectors of the lattice of spacing dx of (a) the nested SPH
// first derivative, |g(k)|^2 with g(k) = sum_j V sin(k.r_j) F_j r_j (eq. 3.16 applied twice),
// and (b) the SPH Laplacian, sum_j V 2(1 - cos k.r_j)(-F_j) (eq. 3.37): the factors by which a
// short wave of the lagged acceleration comes back through the alpha1 term, times rho/|alpha1|.
template <int D>
std::pair<double, double> largestDerivativeSymbols(const Kernel& kernel, double dx) {
  const double support = kernel.supportRadius();
  const int reach = static_cast<int>(std::ceil(support / dx));
  std::vector<Vec<D>> offsets;
  std::vector<double> F;
  const double V = std::pow(dx, D);
  kernel.visit([&](auto shape) {
    using Shape = decltype(shape);
    std::array<int, D> idx;
    idx.fill(-reach);
    while (true) {
      Vec<D> r;
      for (int a = 0; a < D; ++a) r[a] = idx[a] * dx;
      const double rn = r.norm();
      if (rn > 0 && rn < support) {
        offsets.push_back(r);
        F.push_back(kernel.dw_scale / kernel.h * Shape::df_over_q(rn / kernel.h));
      }
      int a = 0;
      while (a < D && ++idx[a] > reach) idx[a++] = -reach;
      if (a == D) break;
    }
  });
  const int samples = D == 2 ? 64 : 24;
  double nested = 0, laplacian = 0;
  std::array<int, D> kidx;
  kidx.fill(0);
  while (true) {
    Vec<D> k;
    for (int a = 0; a < D; ++a) k[a] = M_PI / dx * kidx[a] / samples;
    Vec<D> g = Vec<D>::Zero();
    double lap = 0;
    for (std::size_t n = 0; n < offsets.size(); ++n) {
      const double phase = k.dot(offsets[n]);
      g += (V * std::sin(phase) * F[n]) * offsets[n];
      lap += V * 2.0 * (1.0 - std::cos(phase)) * (-F[n]);
    }
    nested = std::max(nested, g.squaredNorm());
    laplacian = std::max(laplacian, lap);
    int a = 0;
    while (a < D && ++kidx[a] > samples) kidx[a++] = 0;
    if (a == D) break;
  }
  return {nested, laplacian};
}

template <int D>
class SecondOrderFluid final : public PairEffect<D, SecondOrderFluid<D>> {
 public:
  explicit SecondOrderFluid(ConfigTable& cfg) {
    const std::string form = cfg.choice("form", "rivlin_ericksen", {"rivlin_ericksen", "cef"});
    law_.form = form == "cef" ? SecondOrderForm::cef : SecondOrderForm::rivlin_ericksen;
    const std::string d = cfg.choice("derivative", "contravariant", {"contravariant", "covariant", "mixed", "jaumann"});
    law_.derivative = d == "contravariant" ? ConvectedDerivative::contravariant
                      : d == "covariant"   ? ConvectedDerivative::covariant
                      : d == "mixed"       ? ConvectedDerivative::mixed
                                           : ConvectedDerivative::jaumann;
    law_.alpha1 = cfg.number("alpha1", std::nullopt, Bound::any, "Pa s^2");
    law_.alpha2 = cfg.number("alpha2", std::nullopt, Bound::any, "Pa s^2");
    const double procedure = cfg.number("procedure", 3.0, Bound::positive, "");
    if (procedure != 1 && procedure != 2 && procedure != 3 && procedure != 4)
      cfg.fail("procedure", "1, 2, 3 or 4 (thesis §4.4.2 Case 1-4)");
    procedure_ = static_cast<int>(procedure);
    lagged_ = cfg.choice("material_derivative", "lagged", {"lagged", "quasi_steady"}) == "lagged";
  }
  std::string_view name() const override { return "second_order_fluid"; }
  Phase phase() const override { return Phase::gradients; }
  // Reads the velocity gradient of particle i, written in the same pass.
  int passOrder() const override { return 1; }

  void setup(Setup<D>& s) override {
    const std::string me = "effects.second_order_fluid";
    law_.mu = s.viscosity;
    rho0_ = s.rest_density;
    if (!(law_.mu > 0)) throw InputError(me + " needs the viscosity mu: set fluid.viscosity > 0 (Pa s)");
    kappa_ = s.particles.fields.find("velocity_gradient");
    if (!kappa_)
      throw InputError(me + " needs the velocity gradient: add [effects.velocity_gradient]");
    for (const char* other : {"oldroyd_b", "ucm", "xpp"})
      if (s.find(other)) throw InputError(me + " and effects." + other + " are two constitutive models; keep one");

    // The scene must discretise the momentum equation the way the procedure says.
    const std::string proc = me + ".procedure = " + std::to_string(procedure_);
    const bool viscosity = s.find("viscosity") != nullptr, divergence = s.find("stress_divergence") != nullptr;
    const Effect<D>* pressure = s.find("pressure_gradient");
    if (procedure_ == 3 && !viscosity)
      throw InputError(proc + " takes div(tau) as mu lap(v) (thesis eq. 3.37): add [effects.viscosity]");
    if (procedure_ != 3 && viscosity)
      throw InputError(proc + " includes the viscous stress tau = mu A in its own divergence: remove "
                       "[effects.viscosity] (or use procedure 3)");
    if (procedure_ != 4 && !divergence)
      throw InputError(proc + " takes the divergence of the stress by thesis eq. 3.18: add [effects.stress_divergence]");
    if (procedure_ == 4 && divergence)
      throw InputError(proc + " computes div(T) itself from the velocity derivatives: remove [effects.stress_divergence]");
    // Case 1 takes p inside the total stress, so grad(p) is eq. 3.18 (symmetric). Cases 2-4 take
    // it by eq. 3.16 ("difference"); the momentum-conserving eq. 3.18 ("symmetric") is accepted
    // as well: at a die exit the difference form does not push the fluid out of the corner
    // (missing neighbours contribute nothing) and the density there diverges within a
    // millisecond (docs/studies.md, die swell).
    if (pressure && procedure_ == 1 && pressure->form() != "symmetric")
      throw InputError(proc + " takes grad(p) by thesis eq. 3.18: set effects.pressure_gradient.form = \"symmetric\"");
    if (pressure && procedure_ != 1 && pressure->form() != "difference" && pressure->form() != "symmetric")
      throw InputError(proc + " takes grad(p) by thesis eq. 3.16 (or the symmetric eq. 3.18): set "
                       "effects.pressure_gradient.form = \"difference\" or \"symmetric\"");

    extra_ = &s.particles.fields.require("extra_stress", symmetricComponents<D>());
    extra_->extrapolated_to_walls = true;
    extra_->transform = Field::Transform::symmetric_tensor;
    if (procedure_ != 4) {
      elastic_ = &s.particles.fields.require("elastic_stress", D * D);
      elastic_->extrapolated_to_walls = true;  // Fang eq. (46) on wall particles
      elastic_->transform = Field::Transform::tensor;
    }
    wall_velocity_ = s.particles.fields.find("wall_velocity");
    if (lagged_) {
      accel_ = &s.particles.fields.require("lagged_acceleration", D);
      accel_->extrapolated_to_walls = true;
      accel_->transform = Field::Transform::vector;
      // A field, so that it travels with the particles (a run across processes); over every
      // particle, as lagged_acceleration, so that a checkpoint carries both alike (the fixed
      // particles' entries unused).
      previous_velocity_ = &s.particles.fields.require("previous_velocity", D);
      previous_velocity_->refreshed_in_halo = false;  // read by the owner only
      const auto [nested, laplacian] = largestDerivativeSymbols<D>(s.kernel, s.spacing);
      // The alpha1 term of div(eps) is c1 div(G + G^T): c1 lap(a) for a transverse wave, twice
      // that, c1 (lap a + grad div a), for a longitudinal one: the factor 2.
      sigma_max_ = 2.0 * (procedure_ == 4 ? laplacian : nested);
      amplification_ = std::abs(law_.c1()) / rho0_ * sigma_max_;
      if (amplification_ >= 1.0)
        throw InputError(
            me + ": the lagged material derivative DA/Dt is unstable at this resolution: |c1| sigma_max/rho = " +
            std::to_string(amplification_) + " >= 1 (sigma_max = " + std::to_string(sigma_max_) +
            " 1/m^2, the largest symbol of the SPH second derivative on this lattice). Short waves of the "
            "acceleration would grow by that factor every step (c1 = alpha1, or alpha1/2 for CEF). For alpha1 < 0 this mirrors the Hadamard instability "
            "of the second-order fluid itself (waves with k^2 > rho/|alpha1| grow, docs/theory.md). Either coarsen the "
            "particles, reduce |alpha1|, or set material_derivative = \"quasi_steady\" (DA/Dt = 0, exact in steady "
            "flows)");
    }
  }

  void fieldsAllocated(ParticleSet<D>& p) override {
    moving_ = p.n_moving;
    if (lagged_) std::copy(p.velocity.begin(), p.velocity.begin() + D * p.n_moving, previous_velocity_->data.begin());
  }

  void stability(StabilityInputs& in) const override {
    // Without [effects.viscosity] (procedures 1, 2, 4) this effect carries the viscous stress.
    if (procedure_ != 3) in.kinematic_viscosity = std::max(in.kinematic_viscosity, law_.mu / rho0_);
  }

  double stressScale(double velocity, double length) const override {
    const double g = velocity / length;
    return std::max(law_.mu * g, std::abs(law_.alpha1) * g * g + std::abs(law_.alpha2) * g * g);
  }

  void afterStep(const AcceptedStep<D>& step) override {
    if (!lagged_ || !(step.dt > 0)) return;
    double* a = accel_->data.data();
    double* previous = previous_velocity_->data.data();
    const std::size_t n = step.n_moving * D;
    const double inv_dt = 1.0 / step.dt;
#pragma omp parallel for schedule(static) if (step.n_moving >= kParallelMinimum)
    for (std::size_t k = 0; k < n; ++k) {
      a[k] = (step.velocity[k] - previous[k]) * inv_dt;
      previous[k] = step.velocity[k];
    }
  }

  void saveCarried(NamedArrays& out) const override {
    if (!lagged_) return;
    out.emplace_back("lagged_acceleration", accel_->data);
    out.emplace_back("previous_velocity", previous_velocity_->data);
  }
  std::vector<PerParticleArray> carriedPerParticle() const override {
    if (!lagged_) return {};
    return {{"lagged_acceleration", D}, {"previous_velocity", D}};
  }
  void restoreCarried(const ArrayLookup& find) override {
    if (!lagged_) return;
    for (auto [aname, target] : {std::pair{"lagged_acceleration", &accel_->data}, std::pair{"previous_velocity", &previous_velocity_->data}}) {
      const std::vector<double>* values = find(aname);
      // A checkpoint of an older vesph holds the previous velocity of the moving particles only.
      if (values && target == &previous_velocity_->data && values->size() < target->size() &&
          values->size() == static_cast<std::size_t>(D) * moving_) {
        std::copy(values->begin(), values->end(), target->begin());
        continue;
      }
      if (!values || values->size() != target->size())
        throw InputError(std::string("--resume: the checkpoint lacks the lagged material derivative's ") + aname +
                         " (or it has another size)");
      *target = *values;
    }
  }

  void resized(const ParticleSet<D>& p, const ParticleRemap& remap) override {
    if (!lagged_) return;
    // A released particle starts with its velocity as the previous one (no lagged rate yet
    // beyond the buffer's extrapolated value, which the particle set carried over).
    // (The field itself followed the particles with the set.)
    moving_ = p.n_moving;
    double* previous = previous_velocity_->data.data();
    for (std::size_t i = 0; i < remap.newMoving(); ++i)
      if (remap.source[i] >= remap.old_moving)
        for (int a = 0; a < D; ++a) previous[D * i + a] = p.velocity[D * i + a];
  }

  // The pair pass: the gradient of the lagged acceleration (eq. 3.16) and, for procedure 4,
  // the Hessians of the velocity and of the lagged acceleration (eq. 3.36 in D dimensions:
  //   d2f/dx^b dx^c = sum_j V_j (f_i - f_j) F_ij ((D + 2) r^b r^c / r^2 - delta^bc),
  // the thesis' factor 4 being D + 2 for D = 2; its trace is eq. 3.37).
  struct Local {
    Mat<D> grad_a;
    std::array<Mat<D>, D> hv, ha;
    Vec<D> vi, ai;
    const double* v;
    const double* a;
    const double* rho;
    const double* m;
    const double* fixed_velocity;
    std::size_t fixed0;
  };
  Local begin(const RhsContext<D>& ctx, Index i) const {
    const ParticleSet<D>& p = ctx.particles;
    Local l;
    l.grad_a.setZero();
    for (int a = 0; a < D; ++a) {
      l.hv[a].setZero();
      l.ha[a].setZero();
    }
    l.v = p.velocity.data();
    l.a = lagged_ ? accel_->data.data() : nullptr;
    l.vi = p.v(i);
    l.ai = lagged_ ? Vec<D>(Eigen::Map<const Vec<D>>(l.a + D * i)) : Vec<D>::Zero();
    l.rho = p.density.data();
    l.m = p.mass.data();
    l.fixed_velocity = wall_velocity_ ? wall_velocity_->data.data() : p.velocity.data();
    l.fixed0 = wall_velocity_ ? p.n_moving : 0;
    return l;
  }
  void pair(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    const Vec<D> aj = lagged_ ? Vec<D>(Eigen::Map<const Vec<D>>(l.a + D * nb.j)) : Vec<D>::Zero();
    add(l, Eigen::Map<const Vec<D>>(l.v + D * nb.j), aj, nb);
  }
  void pairFixed(const RhsContext<D>&, Index, const Neighbour<D>& nb, Local& l) const {
    // The wall's no-slip ghost: velocity 2 u_w - v~ (the viscous term's), acceleration -a~
    // (the time derivative of that ghost for a wall at rest, a~ extrapolated by Fang eq. 46).
    const Vec<D> aj = lagged_ ? Vec<D>(-Eigen::Map<const Vec<D>>(l.a + D * nb.j)) : Vec<D>::Zero();
    add(l, Eigen::Map<const Vec<D>>(l.fixed_velocity + D * (nb.j - l.fixed0)), aj, nb);
  }
  void end(const RhsContext<D>& ctx, Index i, Local& l) const {
    const Mat<D> K = loadRowMajor<D>(kappa_->data.data() + D * D * i);
    const Mat<D> DA = lagged_ ? SecondOrderFluidLaw::materialDerivative<D>(K, l.grad_a) : Mat<D>::Zero();
    const Mat<D> eps = law_.elastic<D>(K, DA);
    const Mat<D> tau = law_.mu * (K + K.transpose());
    packSymmetric<D>(tau + eps, extra_->data.data() + symmetricComponents<D>() * i);
    if (procedure_ == 3) storeRowMajor<D>(eps, elastic_->data.data() + D * D * i);
    if (procedure_ == 1 || procedure_ == 2) storeRowMajor<D>(tau + eps, elastic_->data.data() + D * D * i);
    if (procedure_ == 4) {
      // div T = mu (lap v + grad div v) + sum_c d(eps)/dx_c e_c, each derivative of eps by the
      // product rule from kappa, its derivatives (the Hessian) and those of grad(a).
      Vec<D> div = Vec<D>::Zero();
      for (int a = 0; a < D; ++a)
        for (int c = 0; c < D; ++c) div[a] += law_.mu * (l.hv[a](c, c) + l.hv[c](c, a));
      for (int c = 0; c < D; ++c) {
        Mat<D> dK, dG;
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            dK(a, b) = l.hv[a](b, c);
            dG(a, b) = l.ha[a](b, c);
          }
        const Mat<D> dDA =
            lagged_ ? SecondOrderFluidLaw::materialDerivativeDerivative<D>(K, dK, dG) : Mat<D>::Zero();
        div += law_.elasticDerivative<D>(K, dK, dDA).col(c);
      }
      const double inv_rho = 1.0 / ctx.particles.density[i];
      for (int a = 0; a < D; ++a) ctx.dvdt[D * i + a] += div[a] * inv_rho;
    }
  }

 private:
  template <class V>
  void add(Local& l, const V& vj, const Vec<D>& aj, const Neighbour<D>& nb) const {
    const double w = l.m[nb.j] / l.rho[nb.j] * nb.F;
    if (lagged_) l.grad_a.noalias() += w * (aj - l.ai) * nb.rij.transpose();
    if (procedure_ != 4) return;
    const Mat<D> P = (D + 2.0) / (nb.r * nb.r) * nb.rij * nb.rij.transpose() - Mat<D>::Identity();
    for (int a = 0; a < D; ++a) {
      l.hv[a] += (w * (l.vi[a] - vj[a])) * P;
      if (lagged_) l.ha[a] += (w * (l.ai[a] - aj[a])) * P;
    }
  }

  SecondOrderFluidLaw law_;
  int procedure_ = 3;
  bool lagged_ = true;
  double rho0_ = 1, amplification_ = 0, sigma_max_ = 0;
  const Field* kappa_ = nullptr;
  const Field* wall_velocity_ = nullptr;
  Field* extra_ = nullptr;
  Field* elastic_ = nullptr;
  Field* accel_ = nullptr;
  Field* previous_velocity_ = nullptr;  // previous_velocity: v at the last accepted step
  std::size_t moving_ = 0;              // the moving particles (an older checkpoint's layout)
};

}  // namespace
VESPH_EFFECT_FACTORY(makeSecondOrderFluid, SecondOrderFluid)
}  // namespace vesph
