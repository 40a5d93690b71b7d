// Debug views of a rendered frame, built from what the renderer reads back (IDs, draw lists, the
// depth pyramid) as RGBA float images for `render --view NAME`.
#pragma once

#include <string>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/render/renderer.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

// Names accepted by --view (besides "shaded", the normal output).
const std::vector<std::string>& debugViewNames();
// What the view needs from the frame.
void prepareViewOptions(const std::string& view, FrameOptions& options);
// Builds the view image (width x height RGBA) from the frame.
Result<std::vector<float>> buildDebugView(const std::string& view, const FrameResult& frame, const Scene& scene,
                                          const Camera& camera, int pyramidLevel = 0);

}  // namespace visbuf::tools
