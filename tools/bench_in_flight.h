// visbuf bench --in-flight (tools/bench_in_flight.cpp) and what it shares with the bench matrix
// (tools/bench_command.cpp) and bench-bake (tools/bench_bake_command.cpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "commands.h"
#include "visbuf/core/result.h"
#include "visbuf/gpu/device.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

// Prints "visbuf bench: error (...)" and returns exit code 1.
int benchFail(const Error& e);
// The bench's camera path: cameras for frames -warmup .. frames-1, a function of frame / frames only.
std::vector<Camera> benchCameraPath(const Scene& scene, uint32_t warmup, uint32_t frames);
std::string utcNow();
double median(std::vector<double> v);  // 0 for none

// Frames in flight against renderFrame for each scene and each of c.inFlight; writes bench.json and bench.md to
// `out`. Exit code 0 or 1.
int runInFlightBench(const BenchCommand& c, gpu::Device& device, const std::vector<Scene>& scenes, uint32_t width,
                     uint32_t height, const std::filesystem::path& out);

}  // namespace visbuf::tools
