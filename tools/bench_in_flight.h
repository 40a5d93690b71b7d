// visbuf bench --in-flight (tools/bench_in_flight.cpp).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "bench_common.h"
#include "commands.h"
#include "visbuf/core/result.h"
#include "visbuf/gpu/device.h"
#include "visbuf/scene/scene.h"

namespace visbuf::tools {

// Frames in flight against renderFrame for each scene and each of c.inFlight; writes bench.json and bench.md to
// `out`. Exit code 0 or 1.
int runInFlightBench(const BenchCommand& c, gpu::Device& device, const std::vector<Scene>& scenes, uint32_t width,
                     uint32_t height, const std::filesystem::path& out);

}  // namespace visbuf::tools
