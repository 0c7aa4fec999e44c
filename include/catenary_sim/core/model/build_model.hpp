// Building the model from a scene (build_model.cpp), and what the built model answers about the
// pass: the statistics section and the speed warning.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "catenary_sim/core/scene/scene.hpp"

namespace catenary_sim {

struct Model;

// Builds the model, solves the design statics (dropper lengths for the presag) and the stability
// limit. Throws SceneError for a scene that cannot be built (e.g. dt above the stability limit).
Model build_model(const Scene& scene);

struct BuildOptions {
  bool stability = true;  // false: skip the stability limit (static probes)
  // Raised supports per section (first, last, first, last, ...), m; empty: from the scene / eq. 6-8.
  std::optional<std::vector<double>> support_rises;
};
Model build_model(const Scene& scene, const BuildOptions& options);

// The statistics section along the line (m): output.analysis_spans, or by default all spans but
// two at each end of the line (of the pass on an endless line).
void analysis_section(const Model& model, double* x0, double* x1);

// A warning (empty if none) for a train speed above 0.7 of the contact wire's wave speed.
std::string speed_warning(const Model& model, double speed_mps);

// Where the mesh is finer than numerics.element_length asks, and so dt shorter than it need be
// (a wire's element falls with its length: a stitch wire's or bridle's clamps a few centimetres
// from their support, a dropper next to another): "" when every element is at least half the
// asked length, else the shortest element, its wire and station, e.g. for a refusal of a pass
// too long to run.
std::string short_element_note(const Model& model);

}  // namespace catenary_sim
