#pragma once
// The particle distribution of a run across MPI processes (core/distribution.hpp's interface;
// docs/architecture.md "Distributed runs"): Zoltan's recursive coordinate bisection for the
// parts, ParticleExchange for the migration and the halo.
#include <cstdlib>
#include <memory>

#include "vesph/core/distribution.hpp"
#include "vesph/core/domain.hpp"
#include "vesph/parallel/communicator.hpp"

namespace vesph {

// cutoff: the kernel support; skin: the neighbour list's (the halo holds every particle within
// cutoff + skin of a part, and the particles are redistributed before any has moved half the
// skin); imbalance_tolerance: the share of the moving particles over the mean above which a
// redistribution repartitions instead of only moving particles across the kept cuts;
// halo_supports: how many kernel supports deep the halo is (1: the pair loops; 2: a step hook
// that composes two neighbourhoods, the ISPH projection's walls: StepHook::haloSupports), the
// halo then holding every particle within halo_supports * cutoff + skin.
template <int D>
std::unique_ptr<ParticleDistribution<D>> makeMpiDistribution(const Domain<D>& domain, double cutoff, double skin,
                                                             double imbalance_tolerance, int halo_supports = 1);

}  // namespace vesph
