// Pass statistics as EN 50318 / EN 50317 use them, in one include: the recorder of a pass
// (pass_recorder.hpp), its figures (force_statistics.hpp), their zero-phase low-pass
// (zero_phase_filter.hpp) and stats.json (statistics_json.hpp).
#pragma once

#include "catenary_sim/core/output/force_statistics.hpp"
#include "catenary_sim/core/output/pass_recorder.hpp"
#include "catenary_sim/core/output/statistics_json.hpp"
#include "catenary_sim/core/output/zero_phase_filter.hpp"
