#include "visbuf/core/image_compare.h"

#include <algorithm>

namespace visbuf {

ImageError compareColor(const std::vector<float>& a, const std::vector<float>& b) {
  ImageError e;
  const size_t pixels = std::min(a.size(), b.size()) / 4;
  if (pixels == 0 || a.size() != b.size()) {
    e.maxAbs = e.meanAbs = 1.0;
    e.psnr = 0.0;
    return e;
  }
  double sumSq = 0.0, sum = 0.0;
  for (size_t p = 0; p < pixels; ++p) {
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) {
      double d = std::abs(double(std::clamp(a[p * 4 + c], 0.0f, 1.0f)) - double(std::clamp(b[p * 4 + c], 0.0f, 1.0f)));
      worst = std::max(worst, d);
      sumSq += d * d;
      sum += d;
    }
    e.maxAbs = std::max(e.maxAbs, worst);
    if (worst > 1.0 / 255.0) ++e.differing;
  }
  e.meanAbs = sum / double(pixels * 3);
  const double mse = sumSq / double(pixels * 3);
  e.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : INFINITY;
  e.differingFraction = double(e.differing) / double(pixels);
  return e;
}

}  // namespace visbuf
