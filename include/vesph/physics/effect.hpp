#pragma once
// The effect interface (docs/architecture.md "Effects"): one physics effect per file, composed by the
// scene. An effect declares the fields it needs at setup and adds its contribution to the
// time derivatives. It never loops over neighbours itself: the pair driver
// (vesph/physics/pair_driver.hpp) runs the neighbour loop (vesph/core/pair_loop.hpp, with the
// threading and Neighbour, the pair geometry) and hands each pair effect the neighbours of one
// particle with the kernel already evaluated.
//
// The right-hand side runs in phases; a phase with no effect in it costs nothing:
//   state      per particle: fields that follow from the state (pressure from density)
//   (walls)    boundary values on fixed particles (vesph/boundary)
//   gradients  pair pass: velocity gradients, number density, ...
//   rates      per particle: constitutive stress rates
//   forces     pair pass: continuity, pressure gradient, viscous and stress terms, stabilisers
//              (a pair pass first runs Effect::prepare of the effects that ask for it)
//   external   per particle: body forces
#include <functional>
#include <span>
#include <utility>
#include <string>
#include <vector>
#include <string_view>

#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/core/pair_loop.hpp"
#include "vesph/core/particles.hpp"

namespace vesph {

enum class Phase { state, gradients, rates, forces, external };

// Everything an effect may read or write during one right-hand-side evaluation.
// Derivative arrays cover the moving particles only (the ODE state).
template <int D>
struct RhsContext {
  ParticleSet<D>& particles;
  const Kernel& kernel;
  const Domain<D>& domain;
  double time;
  double* dxdt;    // [n_moving * D]
  double* drhodt;  // [n_moving]
  double* dvdt;    // [n_moving * D]
  // Rates of the evolving fields (elastic stresses), by the slot Setup::evolve returned;
  // each [n_moving * components].
  double* const* field_rates;
  // The part of the right-hand side being evaluated. An effect whose implicit part is
  // ImplicitPart::linear_rate reads it: it then writes only its explicit or only its implicit
  // term. The system runs an ImplicitPart::all effect only for full and the implicit parts.
  // Under implicit_diagonal every effect with an implicit part writes the diagonal of that
  // part's Jacobian (with respect to its own particle's velocity or stress) instead of its
  // rate, or nothing.
  RhsPart part = RhsPart::full;
};

// What of an effect's contribution an implicit-explicit integrator (arkode-imex) treats
// implicitly: terms linear in the velocities and evolving fields at frozen positions and
// densities (docs/theory.md §9.5). An implicit term also frees the explicit step from its
// stability limit.
//   none         the whole contribution is explicit (the default)
//   all          the whole contribution is implicit (the viscous force; the divergence of an
//                evolving stress whose model is linear_rate); its stability inputs do not
//                bound the explicit step
//   shared       a field both parts read, itself linear in the velocities (the velocity
//                gradient when a linear_rate model reads it): the effect runs in both parts
//   linear_rate  an evolving stress whose rate splits into a part linear in the stress and the
//                velocity gradient (Oldroyd-B, UCM: -S/lambda + (eta_p/lambda)(kappa + kappa^T))
//                and the rest; the linear part is implicit. With the stress divergence implicit
//                too, neither its relaxation time nor its elastic wave speed bounds the step
enum class ImplicitPart { none, all, shared, linear_rate };

// Whether some effect of the scene has an implicit linear stress rate (for the effects whose
// implicit part follows from it: the velocity gradient and the stress divergence).
template <class EffectList>
bool hasLinearRateModel(const EffectList& effects) {
  for (const auto* e : effects)
    if (e->implicitPart() == ImplicitPart::linear_rate) return true;
  return false;
}

// Whether some effect's implicit part reads the velocity gradient (see
// Effect::implicitReadsVelocityGradient).
template <class EffectList>
bool implicitPartReadsVelocityGradient(const EffectList& effects) {
  for (const auto* e : effects)
    if (e->implicitReadsVelocityGradient()) return true;
  return false;
}

// The pressure closure of the scheme (WCSPH: the equation of state). Walls use its
// inverse to give their particles the density that matches the extrapolated pressure.
struct PressureModel {
  virtual ~PressureModel() = default;
  virtual double pressure(double rho) const = 0;
  virtual double densityFor(double p) const = 0;
  virtual double soundSpeed() const = 0;
  // Relative density variation the sound speed was chosen for (delta of thesis eq. 3.38),
  // and the flow speed it was chosen for (V of eq. 3.38); 0 when the sound speed was given.
  virtual double designDensityVariation() const = 0;
  virtual double designVelocity() const = 0;
  virtual double designLength() const = 0;
};

// What effects tell the integrators about explicit stability (Fang eqs. 51-53, thesis 3.5).
struct StabilityInputs {
  double sound_speed = 0;          // max over particles, m/s
  double kinematic_viscosity = 0;  // max, m^2/s
  double elastic_wave_speed = 0;   // sqrt(G/rho) of elastic models, m/s
  double relaxation_time = 0;      // shortest relaxation time, s (0: none)
};

// Named arrays carried between steps (checkpoints, `vesph run --resume`): Effect and StepHook
// save them and look them up by name when restoring.
using NamedArrays = std::vector<std::pair<std::string, std::vector<double>>>;
using ArrayLookup = std::function<const std::vector<double>*(const std::string&)>;
// A carried array with `components` values per particle of the set, in its order (with the halo
// in a run across processes): it travels with the particles (Effect and StepHook
// carriedPerParticle; docs/architecture.md "Distributing more").
struct PerParticleArray {
  std::string name;
  int components = 1;
};

template <int D>
class Effect;

// One row of the implicit part's scalar velocity coupling (Effect::velocityCoupling): the
// derivative of particle i's implicit velocity rate by its own velocity (diagonal) and by
// moving neighbour j's (entries), the same for every component.
struct VelocityCouplingRow {
  double diagonal = 0;
  std::vector<std::pair<Index, double>> entries;
};

// The state an integrator has just accepted (Effect::afterStep): the moving particles'
// positions [n*D], densities [n] and velocities [n*D] at time t, reached by a step of dt.
template <int D>
struct AcceptedStep {
  double t;
  double dt;
  std::size_t n_moving;
  const double* position;
  const double* density;
  const double* velocity;
};

template <int D>
struct Setup {
  ParticleSet<D>& particles;
  const Kernel& kernel;
  double spacing;           // initial particle spacing dx, m
  double rest_density;      // rho0, kg/m^3
  double viscosity;         // dynamic viscosity mu, Pa s
  Vec<D> body_acceleration; // sum of constant body forces, m/s^2
  const PressureModel* pressure_model = nullptr;  // set by the effect that provides one
  std::vector<Field*>* evolving = nullptr;          // the system's evolving fields
  const std::vector<Effect<D>*>* effects = nullptr;  // every effect of the scene

  // The scene's effect of that name, or nullptr (for prerequisites between effects, and for
  // a step hook that runs an effect itself: the ISPH projection's free-surface detection).
  Effect<D>* find(std::string_view name) const {
    for (Effect<D>* e : *effects)
      if (e->name() == name) return e;
    return nullptr;
  }

  // Puts the field's moving-particle values into the ODE state (after the velocities);
  // returns the slot of its rates in RhsContext::field_rates.
  int evolve(Field& f) {
    for (std::size_t k = 0; k < evolving->size(); ++k)
      if ((*evolving)[k] == &f) return static_cast<int>(k);
    evolving->push_back(&f);
    return static_cast<int>(evolving->size() - 1);
  }
};

template <int D>
class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string_view name() const = 0;
  virtual Phase phase() const = 0;
  virtual bool pairwise() const { return false; }
  // Pair effects that read Neighbour::W say so; otherwise the driver skips evaluating it.
  virtual bool needsKernelValue() const { return false; }
  // Within one pair pass the effects run one after another for each particle i. An effect
  // that reads, for particle i, a value another effect of the same pass writes for i (the
  // velocity gradient) runs after it: it returns a higher order. Effects are set up in
  // (phase, passOrder) order as well.
  virtual int passOrder() const { return 0; }
  // The discrete form an effect was configured with, where it has several (pressure_gradient:
  // "symmetric" or "difference"), for effects whose procedure depends on it.
  virtual std::string_view form() const { return {}; }

  // Request fields, check prerequisites (throw InputError with the fix in the message).
  virtual void setup(Setup<D>& s) {}
  // Once the fields requested at setup are allocated (zeros), before anything runs: an effect
  // puts initial per-particle values there (the lagged second-order fluid's previous velocity).
  virtual void fieldsAllocated(ParticleSet<D>& particles) {}
  // A constant body acceleration this effect applies (for wall pressure and sound speed).
  virtual Vec<D> bodyAcceleration() const { return Vec<D>::Zero(); }
  // If this effect is the scheme's pressure closure, return it.
  virtual const PressureModel* pressureModel() const { return nullptr; }
  virtual void stability(StabilityInputs& in) const {}
  // The term an implicit-explicit integrator may treat implicitly (see ImplicitPart).
  virtual ImplicitPart implicitPart() const { return ImplicitPart::none; }
  // Whether that implicit term reads the velocity gradient (field "velocity_gradient"): the
  // gradient is then computed in the implicit evaluations too (ImplicitPart::shared). The linear
  // part of an Oldroyd-B/UCM rate does; so does the stress form of the viscous force.
  virtual bool implicitReadsVelocityGradient() const { return implicitPart() == ImplicitPart::linear_rate; }
  // An implicit term that couples the velocities of neighbours through one scalar per pair,
  // the same for every component (the viscous force), says so and adds particle i's row of
  // that coupling: the assembled preconditioner of arkode-imex's stage solves
  // (OdeSystem::implicitVelocityOperator). A fixed neighbour b's velocity follows the fluid's
  // by wall_dependence[b - n_moving] (Boundary::velocityDependence).
  virtual bool couplesVelocities() const { return false; }
  virtual void velocityCoupling(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                                std::span<const Neighbour<D>> fixed, std::span<const double> wall_dependence,
                                VelocityCouplingRow& row) const {}
  // The scale of the stress an evolving model produces at velocity V over length L (Pa), for
  // default error-control tolerances; 0 when the effect evolves no stress.
  virtual double stressScale(double velocity, double length) const { return 0.0; }
  // The polymer viscosity eta_p (Pa s) of an evolving rate-type model (its zero-shear value:
  // XPP's eta_p), 0 for every other effect (the both-sides diffusion of the stress divergence).
  virtual double polymerViscosity() const { return 0.0; }

  // Called once for every step the integrator accepts (never for rejected steps or stages),
  // for effects that carry information from one step to the next. The right-hand side stays
  // a function of (t, y) within a step.
  virtual void afterStep(const AcceptedStep<D>& step) {}
  // The moving set changed between two steps (an inflow released particles, an outflow removed
  // some; ParticleRemap). The particle set has remapped its arrays and fields already; an
  // effect that keeps other per-particle values from step to step rearranges them here.
  virtual void resized(const ParticleSet<D>& particles, const ParticleRemap& remap) {}
  // What an effect carries from one accepted step to the next (afterStep) that the ODE state
  // does not hold: `vesph run --resume` stores it with every checkpoint (saveCarried appends
  // named arrays) and writes it back before the run goes on (restoreCarried; `find` gives
  // nullptr for a name the checkpoint lacks). An effect with such state must implement both,
  // or a resumed run would start from the values of the initial state. Hooks have the same
  // pair (StepHook).
  virtual void saveCarried(NamedArrays& out) const {}
  virtual void restoreCarried(const ArrayLookup& find) {}
  // The arrays of saveCarried that hold values per particle of the set (PerParticleArray).
  virtual std::vector<PerParticleArray> carriedPerParticle() const { return {}; }

  // Per-particle preparation for a pair effect, for values that the pair term reads for every
  // neighbour j and that are expensive per pair (the artificial stress R_j, Fang eqs. 40-44):
  // PairDriver::run calls prepare, for each effect of the pass whose prepares() is true,
  // before the neighbour loop of that pass (so after the state phase and the walls), over
  // disjoint ranges [begin, end) that together cover ALL particles, moving [0, n_moving) and
  // fixed [n_moving, N), in parallel (OpenMP, by the driver). It writes only to the particles
  // of its range and must not throw. A pass without such an effect runs no extra code.
  virtual bool prepares() const { return false; }
  virtual void prepare(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const {}

  // A pair effect whose result for particle i depends on its neighbours' results of the same
  // pass (free_surface with method = "marrone" and a threshold: is an outermost particle
  // within the support?) asks for a second sweep: PairDriver::run then calls interactAgain,
  // after every interact of the pass has finished, for each moving particle for which
  // sweepAgain(ctx, i) is true (the others' neighbours are not gathered again). A pass without
  // such an effect runs no second sweep.
  virtual bool secondSweep() const { return false; }
  virtual bool sweepAgain(const RhsContext<D>& ctx, Index i) const { return true; }
  virtual void interactAgain(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                             std::span<const Neighbour<D>> fixed) const {}

  // A forces-phase effect that also needs a neighbour sum of its own before its pair term (the
  // density diffusion's renormalised density gradient, form = "antuono", which the pair term
  // reads at every neighbour j) returns that sum here: a gradients-phase pair effect that it
  // owns and sets up itself. The system runs it in the gradients pass, after which a run across
  // processes refreshes the fields on the ghosts, so the forces pass reads every neighbour's
  // value. nullptr (the default): no such pass.
  virtual Effect<D>* gradientsPart() { return nullptr; }

  // Per-particle effects: moving particles [begin, end).
  virtual void particles(const RhsContext<D>& ctx, std::size_t begin, std::size_t end) const {}
  // Pair effects: particle i with its moving and fixed neighbours (within the support).
  virtual void interact(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                        std::span<const Neighbour<D>> fixed) const {}
};

// Base for pair effects: the derived struct supplies the per-pair function and never loops.
//   Local begin(ctx, i)                      per-particle accumulator
//   void pair(ctx, i, nb, Local&)            a moving neighbour
//   void pairFixed(ctx, i, nb, Local&)       a fixed neighbour (defaults to pair)
//   void end(ctx, i, Local&)                 write the result for particle i
template <int D, class Derived>
class PairEffect : public Effect<D> {
 public:
  bool pairwise() const final { return true; }
  void interact(const RhsContext<D>& ctx, Index i, std::span<const Neighbour<D>> moving,
                std::span<const Neighbour<D>> fixed) const final {
    const Derived& self = static_cast<const Derived&>(*this);
    auto local = self.begin(ctx, i);
    for (const Neighbour<D>& nb : moving) self.pair(ctx, i, nb, local);
    for (const Neighbour<D>& nb : fixed) self.pairFixed(ctx, i, nb, local);
    self.end(ctx, i, local);
  }

  template <class Local>
  void pairFixed(const RhsContext<D>& ctx, Index i, const Neighbour<D>& nb, Local& acc) const {
    static_cast<const Derived&>(*this).pair(ctx, i, nb, acc);
  }
};

}  // namespace vesph
