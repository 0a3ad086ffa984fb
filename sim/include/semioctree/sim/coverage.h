// Survey coverage (simulation only): which of the scene's ground-truth surface samples a
// survey measured, against a cached reference of the samples a grid of scan positions can
// see. The design is described in docs/coverage.md; this header includes the parts.
#pragma once

#include "semioctree/sim/coverage/measure.h"
#include "semioctree/sim/coverage/misses.h"
#include "semioctree/sim/coverage/plan.h"
#include "semioctree/sim/coverage/reference.h"
#include "semioctree/sim/coverage/visibility.h"
