#pragma once
// Constitutive models (seed thesis §2.3; Fang et al. 2006 §2; Xu et al. 2013).
//
// A model is a pure rate function (docs/architecture.md "Effects"): given the velocity gradient
// kappa (kappa_ab = dv_a/dx_b, Fang eq. 23) and its own elastic stress S, it returns dS/dt.
// No time step, no half steps: the integrator owns time. ConstitutiveEffect<D, Model> turns a
// model into an effect: it registers the elastic stress as an evolving field of the ODE state
// (so a Newtonian scene carries none), reads the velocity gradient, calls the model for every
// moving particle and writes the full extra stress T = S + eta_s (kappa + kappa^T) for output.
// Adding a model: one file with a struct deriving from ConstitutiveEffect, one registration
// line in src/physics/registry.cpp.
//
// Symmetric tensors are stored as 3 components in 2D (xx, xy, yy) and 6 in 3D
// (xx, xy, xz, yy, yz, zz), the order of the output's extra_stress.
//
// Out-of-plane stress in 2D. 2D is planar flow (v_z = 0, d/dz = 0): S_xz = S_yz = 0 stay zero,
// but S_zz obeys dS_zz/dt = rate(kappa, S)_zz, which is zero for a model linear in S with a
// zero initial S_zz (Oldroyd-B, UCM: S_zz = 0 for all time, 3 components suffice) but not for
// a model whose relaxation couples the components through invariants (XPP: tr(S), tr(S.S)).
// Such a model declares  static constexpr bool kOutOfPlaneStress = true;  and a rate that
// accepts 3x3 tensors; in 2D the effect then also evolves "elastic_stress_zz" (1 component,
// written as extra_stress_zz) and calls the rate on the 3x3 tensors with kappa and S embedded
// (kappa_za = kappa_az = 0, S_xz = S_yz = 0). "elastic_stress" keeps its 3 components, so the
// stress divergence, the walls and the output are unchanged.
#include <Eigen/Dense>

#include <sstream>
#include <string>

#include "vesph/physics/effect.hpp"

namespace vesph {

template <int D>
using Mat = Eigen::Matrix<double, D, D>;

template <int D>
constexpr int symmetricComponents() {
  return D == 2 ? 3 : 6;
}

template <int D>
Mat<D> unpackSymmetric(const double* s) {
  Mat<D> m;
  if constexpr (D == 2) {
    m << s[0], s[1], s[1], s[2];
  } else {
    m << s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5];
  }
  return m;
}

template <int D>
void packSymmetric(const Mat<D>& m, double* s) {
  if constexpr (D == 2) {
    s[0] = m(0, 0); s[1] = 0.5 * (m(0, 1) + m(1, 0)); s[2] = m(1, 1);
  } else {
    s[0] = m(0, 0); s[1] = 0.5 * (m(0, 1) + m(1, 0)); s[2] = 0.5 * (m(0, 2) + m(2, 0));
    s[3] = m(1, 1); s[4] = 0.5 * (m(1, 2) + m(2, 1)); s[5] = m(2, 2);
  }
}

// Particle i's stress from a field of stresses: packed symmetric (the rate-type models' elastic
// stress, symmetricComponents<D>() per particle) or, with full, the D x D row-major tensor of
// the second-order fluid.
template <int D>
Mat<D> loadStress(const double* S, bool full, std::size_t i) {
  if (full) return Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>>(S + D * D * i);
  return unpackSymmetric<D>(S + symmetricComponents<D>() * i);
}

// Whether a model needs S_zz in planar flow (see above); false unless it says so.
template <class Model>
constexpr bool hasOutOfPlaneStress() {
  if constexpr (requires { Model::kOutOfPlaneStress; })
    return Model::kOutOfPlaneStress;
  else
    return false;
}

// Base of the models that evolve an elastic stress S. Model supplies
//   Mat<D> rate(const Mat<D>& kappa, const Mat<D>& S) const     dS/dt
//     (for kOutOfPlaneStress models: also Mat<3> rate(const Mat<3>&, const Mat<3>&) in 2D)
//   double polymerViscosity() const override, double relaxationTime() const  (scales, stability:
//     modulus G = eta_p/lambda for the elastic wave speed)
// and optionally
//   double shortestRelaxationTime() const   the relaxation step limit's time (default lambda)
//   Mat<D> linearRate(const Mat<D>& kappa, const Mat<D>& S) const   the part of the rate
//     linear in kappa and S (Oldroyd-B: -S/lambda + (eta_p/lambda)(kappa + kappa^T)), for
//     implicit-explicit integrators: the effect's implicit part is then that term and its
//     explicit part the rest of the rate (ImplicitPart::linear_rate; docs/theory.md §9.5).
//     Models whose relaxation is nonlinear in S (XPP) stay explicit.
template <int D, class Model>
class ConstitutiveEffect : public Effect<D> {
 public:
  Phase phase() const override { return Phase::rates; }

  void setup(Setup<D>& s) override {
    const Field* kappa = s.particles.fields.find("velocity_gradient");
    if (!kappa)
      throw InputError("effects." + std::string(this->name()) +
                       " needs the velocity gradient: add [effects.velocity_gradient]");
    kappa_ = kappa;
    stress_ = &s.particles.fields.require("elastic_stress", symmetricComponents<D>());
    stress_->extrapolated_to_walls = true;  // Fang eq. (46) on wall particles
    stress_->transform = Field::Transform::symmetric_tensor;
    slot_ = s.evolve(*stress_);
    if constexpr (outOfPlane()) {
      zz_ = &s.particles.fields.require("elastic_stress_zz", 1);
      zz_->extrapolated_to_walls = true;  // for the output only: no force uses S_zz
      slot_zz_ = s.evolve(*zz_);
    }
    extra_ = &s.particles.fields.require("extra_stress", symmetricComponents<D>());
    extra_->extrapolated_to_walls = true;
    extra_->transform = Field::Transform::symmetric_tensor;
    solvent_viscosity_ = s.viscosity;
    // The solvent stress eta_s (kappa + kappa^T) goes into extra_stress; it acts only through
    // [effects.viscosity]. Without it the output would show a stress no force applies.
    if (solvent_viscosity_ > 0 && !s.find("viscosity"))
      throw InputError("effects." + std::string(this->name()) + ": fluid.viscosity = " +
                       std::to_string(solvent_viscosity_) +
                       " Pa s is the solvent viscosity, but the scene has no [effects.viscosity] to apply it: add "
                       "[effects.viscosity], or set fluid.viscosity = 0 for a fluid without solvent");
    rho0_ = s.rest_density;
  }

  void stability(StabilityInputs& in) const override {
    const Model& m = static_cast<const Model&>(*this);
    const double lambda = m.relaxationTime();
    // Elastic shear waves travel at sqrt(G/rho), G = eta_p/lambda.
    if (lambda > 0) in.elastic_wave_speed = std::max(in.elastic_wave_speed, std::sqrt(m.polymerViscosity() / (lambda * rho0_)));
    double shortest = lambda;
    if constexpr (requires { m.shortestRelaxationTime(); }) shortest = m.shortestRelaxationTime();
    if (shortest > 0) in.relaxation_time = in.relaxation_time > 0 ? std::min(in.relaxation_time, shortest) : shortest;
  }

  ImplicitPart implicitPart() const override {
    return hasLinearRate() ? ImplicitPart::linear_rate : ImplicitPart::none;
  }

  double stressScale(double velocity, double length) const override {
    return static_cast<const Model&>(*this).polymerViscosity() * velocity / length;
  }

  void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const override {
    const Model& m = static_cast<const Model&>(*this);
    if constexpr (hasLinearRate()) {
      if (ctx.part != RhsPart::full) {
        splitParticles(ctx, begin, end);
        return;
      }
    }
    const double* k = kappa_->data.data();
    const double* S = stress_->data.data();
    double* dS = ctx.field_rates[slot_];
    double* T = extra_->data.data();
    constexpr int nc = symmetricComponents<D>();
    std::size_t i = begin;
    try {
      for (; i < end; ++i) {
        const Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>> kappa(k + D * D * i);
        const Mat<D> Si = unpackSymmetric<D>(S + nc * i);
        if constexpr (outOfPlane()) {
          // planar flow embedded in 3D: the 3x3 rate, of which xz and yz vanish
          Mat<3> kappa3 = Mat<3>::Zero(), S3 = Mat<3>::Zero();
          kappa3.template topLeftCorner<2, 2>() = kappa;
          S3.template topLeftCorner<2, 2>() = Si;
          S3(2, 2) = zz_->data[i];
          const Mat<3> R = m.rate(kappa3, S3);
          packSymmetric<2>(R.template topLeftCorner<2, 2>(), dS + nc * i);
          ctx.field_rates[slot_zz_][i] = R(2, 2);
        } else {
          packSymmetric<D>(m.rate(kappa, Si), dS + nc * i);
        }
        packSymmetric<D>(Si + solvent_viscosity_ * (kappa + kappa.transpose()), T + nc * i);
      }
    } catch (const NumericalFailure& e) {
      std::ostringstream os;
      os << e.what() << " (fluid particle id " << ctx.particles.id[i] << " at t = " << ctx.time << " s)";
      throw NumericalFailure(os.str());
    }
  }

 protected:
  static constexpr bool hasLinearRate() {
    return !outOfPlane() && requires(const Model& m, const Mat<D>& k) { m.linearRate(k, k); };
  }

 private:
  // One part of the rate of a model with a linear part L(kappa, S): the implicit part is L, the
  // explicit part the rest of the rate (rate - L); their sum is the rate to round-off. The
  // extra stress for output is written by the explicit part.
  void splitParticles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const {
    const Model& m = static_cast<const Model&>(*this);
    const double* k = kappa_->data.data();
    const double* S = stress_->data.data();
    double* dS = ctx.field_rates[slot_];
    double* T = extra_->data.data();
    constexpr int nc = symmetricComponents<D>();
    const bool implicit = ctx.part == RhsPart::implicit_part;
    if (ctx.part == RhsPart::implicit_diagonal) {
      // The diagonal of the linear rate's stress block: L(0, S) with S = 1 in every component
      // (exact for a rate diagonal in S, -S/lambda).
      double diagonal[nc];
      packSymmetric<D>(m.linearRate(Mat<D>::Zero(), Mat<D>::Ones()), diagonal);
      for (std::size_t i = begin; i < end; ++i)
        for (int c = 0; c < nc; ++c) dS[nc * i + c] = diagonal[c];
      return;
    }
    for (std::size_t i = begin; i < end; ++i) {
      const Eigen::Map<const Eigen::Matrix<double, D, D, Eigen::RowMajor>> kappa(k + D * D * i);
      const Mat<D> Si = unpackSymmetric<D>(S + nc * i);
      if (implicit) {
        packSymmetric<D>(m.linearRate(kappa, Si), dS + nc * i);
      } else {
        packSymmetric<D>(m.rate(kappa, Si) - m.linearRate(kappa, Si), dS + nc * i);
        packSymmetric<D>(Si + solvent_viscosity_ * (kappa + kappa.transpose()), T + nc * i);
      }
    }
  }

 private:
  // (a function, not a constant: Model is incomplete where this base is instantiated)
  static constexpr bool outOfPlane() { return D == 2 && hasOutOfPlaneStress<Model>(); }
  const Field* kappa_ = nullptr;
  Field* stress_ = nullptr;
  Field* zz_ = nullptr;  // S_zz in 2D for kOutOfPlaneStress models
  Field* extra_ = nullptr;
  int slot_ = -1, slot_zz_ = -1;
  double solvent_viscosity_ = 0, rho0_ = 1;
};

}  // namespace vesph
