// Stages 6–7 (paper 2.2 "NBV calculation", Eq 3–5): Next-Best-View candidates,
// their scores and the stop percentage. The rules are in docs/nbv.md.
#pragma once

#include "semioctree/nbv/candidates.h"
#include "semioctree/nbv/overlap.h"
#include "semioctree/nbv/params.h"
#include "semioctree/nbv/room.h"
#include "semioctree/nbv/rooms.h"
#include "semioctree/nbv/scoring.h"
