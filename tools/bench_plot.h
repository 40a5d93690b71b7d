// The time-against-error plot of `visbuf bench`: plain SVG text, one panel per scene size.
#pragma once

#include <string>
#include <vector>

namespace visbuf::tools {

struct PlotPoint {
  std::string path;   // "visbuf" | "forward": marker shape
  std::string cull;   // "none" | "frustum" | "occlusion": colour
  std::string label;  // drawn beside the point (the LOD threshold)
  double timeMs = 0;  // x, log scale
  double psnr = 0;    // y, dB; +inf is drawn on the top edge and labelled "exact"
  bool pareto = false;
};

struct PlotPanel {
  std::string title;
  std::vector<PlotPoint> points;
};

// Which points are on the Pareto front (no other point is at least as fast and at least as accurate,
// and strictly better in one). PSNRs within psnrTolerance dB count as equal (raster noise between the
// two paths is a few hundredths of a dB); equal points are all kept.
std::vector<bool> paretoFront(const std::vector<double>& timeMs, const std::vector<double>& psnr,
                              double psnrTolerance = 0.1);

// The whole figure: title, a subtitle line (e.g. the command), panels side by side, a shared legend.
std::string renderBenchSvg(const std::vector<PlotPanel>& panels, const std::string& title,
                           const std::string& subtitle);

}  // namespace visbuf::tools
