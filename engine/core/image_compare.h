// Image error metrics used by tests, `render --reference` and benchmarks: every speed figure is
// reported beside the error it costs.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace visbuf {

struct ImageError {
  double maxAbs = 0.0;    // largest per-channel absolute difference (RGB, values clamped to [0,1])
  double meanAbs = 0.0;
  double psnr = INFINITY; // dB, peak 1.0
  size_t differing = 0;   // pixels whose largest channel difference exceeds 1/255
  double differingFraction = 0.0;
};

// Compares two RGBA float images of the same size (alpha ignored).
ImageError compareColor(const std::vector<float>& a, const std::vector<float>& b);

}  // namespace visbuf
