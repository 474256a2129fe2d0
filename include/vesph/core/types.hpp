#pragma once
// Basic types shared by the whole library. Units are SI everywhere.
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace vesph {

using Index = std::uint32_t;

// Loops over fewer items than this run on one thread: starting an OpenMP team costs more than
// the work, and on a loaded machine a barrier can wait for a descheduled thread for
// milliseconds (a 1000-particle channel ran 7x slower on two contended threads than on one).
inline constexpr std::size_t kParallelMinimum = 4096;
// Loops over plain state values (copies, axpy: a few flops per value) go parallel only above
// this many values; below it the OpenMP fork/join costs more than the loop, and on a loaded
// machine much more.
constexpr std::size_t kParallelMinimumValues = std::size_t{1} << 17;

template <int D>
using Vec = Eigen::Matrix<double, D, 1>;

// Particle kinds as written to the output (`kind` dataset, docs/user-guide.md, output format).
enum class ParticleKind : std::uint8_t {
  fluid = 0,   // moving particles, part of the ODE state
  wall = 1,    // fixed wall particles in contact with the fluid
  dummy = 2,   // fixed dummy/image layers behind the wall
  inflow = 3,  // inflow buffer particles (prescribed motion)
};

// Which part of the right-hand side f = f_E + f_I an evaluation computes: all of it, the
// explicit (non-stiff) part or the implicit (stiff, linear) part of an implicit-explicit
// integrator (docs/theory.md §9.5). Each effect declares its implicit part
// (Effect::implicitPart). implicit_diagonal: instead of the implicit part's rates, the diagonal
// of its Jacobian with respect to the velocities and evolving fields at the given positions
// (the IMEX integrator's Jacobi preconditioner).
enum class RhsPart : std::uint8_t { full, explicit_part, implicit_part, implicit_diagonal };

// Invalid user input (scene, command line). Exit code 2.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// NaN/Inf, blow-up, or a failed solve during a run. Exit code 3.
struct NumericalFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A numerical failure that every process of a run across processes meets alike, decided from
// reduced quantities (ARKODE's error test over the global norm, the frame's finiteness check):
// the processes end together, as a serial run does. Any other NumericalFailure may be one
// process's alone (a model's, inside its right-hand side), and then ends every process at once.
struct SharedNumericalFailure : NumericalFailure {
  using NumericalFailure::NumericalFailure;
};

}  // namespace vesph
