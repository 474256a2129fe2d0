#pragma once
// The hook interface lives in vesph/physics/step_hook.hpp (below sim/, so that boundaries and
// the projection implement hooks without including sim/); this header only forwards to it.
#include "vesph/physics/step_hook.hpp"
