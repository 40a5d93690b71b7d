// What the bench commands share (tools/bench_common.cpp): bench, bench --in-flight and bench-bake.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "visbuf/core/result.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

// Prints "visbuf bench: error (...)" and returns exit code 1.
int benchFail(const Error& e);
// The bench's camera path: cameras for frames -warmup .. frames-1, a function of frame / frames only.
std::vector<Camera> benchCameraPath(const Scene& scene, uint32_t warmup, uint32_t frames);
std::string utcNow();                  // ISO 8601, seconds, UTC
double median(std::vector<double> v);  // 0 for none

}  // namespace visbuf::tools
