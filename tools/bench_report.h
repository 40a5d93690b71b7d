// The outputs of the `visbuf bench` matrix (measured in tools/bench_command.cpp): bench.json, bench.csv, bench.md
// and bench.svg (time-vs-PSNR plot with the Pareto front), and the labels the console lines share with them.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "visbuf/core/result.h"
#include "visbuf/render/renderer.h"

namespace visbuf::tools {

// One configuration of the matrix.
struct BenchConfig {
  RenderPath path;
  CullMode cull;
  float lod;          // <= 0: off
  std::string lodLabel;
  bool wideIds = false;  // visbuf: the 64-bit ID target forced where the renderer would pick 32 bits
  bool quantized = false;  // vertices quantised as `bake --quantize` stores them (pack round trip in memory)
  uint32_t msaa = 1;       // samples per pixel (FrameOptions::msaa); its reference renders at the same count
  ShadingMode shading = ShadingMode::Auto;  // visbuf only
  SwRasterMode swRaster = SwRasterMode::Auto;  // visbuf only
};

// One configuration measured on one scene size.
struct BenchRow {
  uint32_t objects = 0;
  BenchConfig config;
  std::vector<std::pair<std::string, std::pair<double, double>>> passMs;  // name -> median, p95
  double frameMedian = 0, frameP95 = 0, gpuMedian = 0, gpuP95 = 0, cpuMedian = 0, wallMedian = 0;
  double trianglesMedian = 0, drawnMedian = 0;
  // Visbuf, single-sampled: triangles drawn per covered pixel (median; a visibility buffer's ideal is about 1);
  // 0 where the path does not count covered pixels.
  double trianglesPerCoveredPixel = 0;
  uint64_t sceneBytes = 0, targetBytesPerPixel = 0;
  // One extra (untimed) frame at the last measured camera with countOverdraw: depth-passing raster writes per
  // pixel and the bytes written per pixel (FrameStats::bytesWrittenPerPixel).
  double rasterWritesPerPixel = 0, bytesWrittenPerPixel = 0;
  double perSamplePixels = 0;  // visbuf MSAA: median pixels shaded per distinct sample ID
  double psnrMean = INFINITY, psnrWorst = INFINITY, maxAbs = 0, meanAbs = 0, differingFraction = 0;
  std::optional<uint64_t> idMismatches;  // pixels over all measured frames; empty: not comparable
  uint64_t idPixels = 0;
  std::string reference;
  std::string idBits;  // "32" / "64": bits per pixel of the visbuf ID target; "-": forward (none)
  std::string shading = "-";  // visbuf: the shading mode used (uber / classified); "-": other paths
  std::string raster = "hw";  // visbuf: "hw+sw" where the last measured frame used the software micro-raster
  double materialsPresent = 0, classifiedTiles = 0;  // classified: medians over the measured frames
  bool pareto = false;
};

// One scene size and the reference its rows are compared with.
struct BenchSceneInfo {
  uint32_t objects = 0;  // as asked (0: the file's own)
  uint32_t sceneObjects = 0;
  uint64_t triangles = 0;
  std::string reference;
  std::string referenceReason;
  double referenceFrameMsMedian = 0;
};

struct BenchResults {
  nlohmann::json skipped = nlohmann::json::array();  // {path, cull, reason} of the combinations not run
  std::vector<BenchSceneInfo> scenes;
  std::vector<BenchRow> rows;  // scene by scene, in configuration order
};

// "visbuf", or "visbuf 4x" with MSAA (tables).
std::string pathLabel(const BenchConfig& k);
// A PSNR with two decimals, or "inf" for identical images.
std::string dbText(double db);

// Pareto front per scene size: lower frame time, higher PSNR (mean; within 0.1 dB counts as equal).
void markParetoFront(std::vector<BenchRow>& rows);

// bench.csv, bench.md, bench.svg and bench.json in c.output, each written atomically; the first failed write's
// error.
Status writeBenchReport(const BenchCommand& c, const BenchResults& results, const std::string& deviceName,
                        uint32_t width, uint32_t height);

}  // namespace visbuf::tools
