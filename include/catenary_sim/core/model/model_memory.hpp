// The model's memory, estimated from the scene before anything is allocated (model_memory.cpp).
#pragma once

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

struct Model;

// Memory per wire node (bytes) to build a model and solve its statics: measured as the peak
// resident size of simulate_pass on the reference scene at 1.1e5-2.2e5 nodes (2026-11-23:
// 1.2-1.3 kB a node over a 25 MB base), with a margin of 1.5 for other scenes.
constexpr double kModelBytesPerNode = 2048.0;
// The model's size estimated from the scene before anything is allocated, and the limit (half the
// machine's physical memory). check_model_memory throws SceneError with both, naming what to change.
double estimate_model_bytes(const Scene& scene);
double estimate_wind_field_bytes(const Scene& scene);  // its turbulent wind field's share (0 without)
double model_memory_limit_bytes();
void check_model_memory(const Scene& scene);

// The train front's travel over a whole pass, m (on an endless line, from where the block starts it).
double pass_distance(const Model& model);
// Steps a whole pass takes at the scene's train speed (inf at speed 0): offline tools refuse a
// pass above their bound unless asked for.
double pass_step_count(const Model& model);

}  // namespace catenary_sim
