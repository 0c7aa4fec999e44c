// The line's design statics: the heights of the wires and the lengths and tensions of the droppers
// that hold the contact wire at its design shape, and the support preloads.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/model/model.hpp"

namespace catenary_sim {

// section_supports: per section, the station of each of its supports.
void design_statics(const Scene& scene, const std::vector<std::vector<double>>& section_supports, Model& m);

// A bridle's arm in the model's small angles: at a slope of 1 in 4 an arm's pull is 3 % off its
// tension's true share (tan against sin). Its rise in the V from the middle to its end `end`.
constexpr double kSteepestBridleArm = 0.25;
double bridle_arm_rise(const Wire& bridle, int end);
// Hangs bridle w at its spec's tension (its band assembled for it) from its middle at the working
// height, under its weight and its clamps' static forces (m's); returns its steeper arm's rise in
// the V, w's heights and slopes and the middle's reaction set.
double hang_bridle(const Scene& scene, const Model& m, Wire& w, std::vector<double>& reaction);
// Refuses (SceneError, by the section's bridle.tension) the bridle whose steepest arm, `slope`
// (above kSteepestBridleArm), is told of by `how`; `advice` is added to raising the tension: to
// `needed` where known (the statics done again at a second tension), else the tension at which
// the slope would fall as 1 / tension.
[[noreturn]] void refuse_slack_bridle(const Scene& scene, const Wire& bridle, double slope, const std::string& how,
                                      const std::string& advice = "", std::optional<double> needed = std::nullopt);

}  // namespace catenary_sim
