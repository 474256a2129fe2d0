#pragma once
// The SPH discretisation as an ODE right-hand side (DESIGN.md "The shape"):
//   rhs(t, y, ydot): unpack y into the particle set -> neighbour search -> each active effect
//                    adds its contribution, phase by phase -> pack ydot
// The state vector holds the moving particles only: [positions n*D | densities n |
// velocities n*D]. Fixed particles (walls) live in the particle set and never enter it.
#include <functional>
#include <memory>
#include <vector>

#include "vesph/boundary/boundary.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/core/kernel.hpp"
#include "vesph/core/neighbours.hpp"
#include "vesph/physics/effect.hpp"
#include "vesph/physics/pair_driver.hpp"
#include "vesph/sim/step_hook.hpp"
#include "vesph/time/integrator.hpp"

namespace vesph {

template <int D>
class SphSystem final : public OdeSystem {
 public:
  ParticleSet<D> particles;
  Domain<D> domain;
  Kernel kernel;
  NeighbourList<D> neighbours;
  PairDriver<D> driver;
  std::vector<std::unique_ptr<Effect<D>>> effects;
  std::vector<std::unique_ptr<Boundary<D>>> boundaries;
  // Run after every accepted step, in order, before the effects' afterStep and the observer
  // (the ISPH projection, src/isph).
  std::vector<std::unique_ptr<StepHook<D>>> hooks;
  // Called by afterStep (diagnostics, checks, interruption); returns false to stop.
  std::function<bool(double t, double dt, double* y)> observer;

  // Sets up boundaries and effects (field requests, prerequisites) and sorts the effects
  // into their phases. Call once the particles exist.
  void setup(double spacing, double rest_density, double viscosity, double skin);

  std::size_t size() const override;
  StateSegments segments() const override;
  void rhs(double t, const double* y, double* ydot) override;
  // The same evaluation without counting it (derived fields for output, tests).
  void evaluate(double t, const double* y, double* ydot);
  StabilitySnapshot stability() const override;
  bool afterStep(double t, double dt, double* y) override;
  bool afterStepChangesState() const override;
  bool mayResize() const override;
  bool resizePending() const override;
  double* resizeState(double t, double* y) override;
  // Checkpoints of scenes whose particle set changes (`vesph run --resume`): the next id a
  // released particle gets, and the rebuild of the moving set as a checkpoint lists it. The
  // moving particles become those of `moving_ids`, in that order: a particle of the current
  // set keeps its values, any other is created (from a fixed particle's values, for the caller
  // to overwrite with the checkpoint's state) with that id, through the same remap as an
  // inflow release, so effects, boundaries and hooks follow (resized). The fixed particles
  // stay as they are.
  std::uint64_t nextId() const { return next_id_; }
  void setNextId(std::uint64_t id) { next_id_ = id; }
  void rebuildMovingSet(const std::vector<std::uint64_t>& moving_ids);
  // The buffer the integrator works on (owned by the Simulation): resizeState resizes it.
  std::vector<double>* state_buffer = nullptr;
  // Called after every particle-count change with the rewritten state (the Simulation's copy
  // of the last good state must follow it).
  std::function<void(double t, const double* y)> resize_observer;

  void pack(double* y) const;
  void unpack(const double* y);

  const PressureModel* pressureModel() const { return pressure_model_; }
  const std::vector<Field*>& evolvingFields() const { return evolving_; }
  Vec<D> bodyAcceleration() const { return body_acceleration_; }
  std::uint64_t rhsEvaluations() const { return rhs_evals_; }

 private:
  void particlePass(const std::vector<Effect<D>*>& list, const RhsContext<D>& ctx);
  // remap_ applied to the particle set, effects, boundaries, hooks and the neighbour structures.
  void applyRemap();

  std::vector<Effect<D>*> state_, gradients_, rates_, forces_, external_;
  std::vector<Field*> evolving_;
  std::vector<double*> field_rates_;
  StabilityInputs stability_inputs_;
  const PressureModel* pressure_model_ = nullptr;
  Vec<D> body_acceleration_ = Vec<D>::Zero();
  double max_speed_ = 0, max_acceleration_ = 0;
  std::uint64_t rhs_evals_ = 0;
  std::uint64_t next_id_ = 0;
  ParticleChanges changes_;
  ParticleRemap remap_;
  std::vector<char> removed_flag_;
  // Whether some hook answers true (hook is a StepHook member predicate).
  template <class Pred>
  bool anyHook(Pred pred) const {
    for (const auto& hk : hooks)
      if (((*hk).*pred)()) return true;
    return false;
  }
};

}  // namespace vesph
