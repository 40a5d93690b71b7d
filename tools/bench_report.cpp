#include "bench_report.h"

#include <algorithm>
#include <filesystem>

#include <fmt/format.h>

#include "bench_in_flight.h"
#include "bench_plot.h"
#include "invocation.h"
#include "stats_output.h"

namespace visbuf::tools {

std::string pathLabel(const BenchConfig& k) {
  return k.msaa > 1 ? fmt::format("{} {}x", renderPathName(k.path), k.msaa) : std::string(renderPathName(k.path));
}

std::string dbText(double db) { return std::isfinite(db) ? fmt::format("{:.2f}", db) : std::string("inf"); }

void markParetoFront(std::vector<BenchRow>& rows) {
  std::vector<uint32_t> sizes;
  for (const BenchRow& row : rows)
    if (std::find(sizes.begin(), sizes.end(), row.objects) == sizes.end()) sizes.push_back(row.objects);
  for (uint32_t objects : sizes) {
    std::vector<size_t> idx;
    std::vector<double> t, q;
    for (size_t i = 0; i < rows.size(); ++i)
      if (rows[i].objects == objects) {
        idx.push_back(i);
        t.push_back(rows[i].frameMedian);
        q.push_back(std::isfinite(rows[i].psnrMean) ? rows[i].psnrMean : 1e300);
      }
    std::vector<bool> front = paretoFront(t, q);
    for (size_t j = 0; j < idx.size(); ++j) rows[idx[j]].pareto = front[j];
  }
}

namespace {

nlohmann::json dbJson(double db) { return std::isfinite(db) ? nlohmann::json(db) : nlohmann::json("inf"); }

std::string objectsLabel(uint32_t n) { return n ? fmt::format("{}", n) : std::string("file"); }

nlohmann::json rowJson(const BenchRow& row) {
  nlohmann::json x;
  x["objects"] = row.objects;
  x["path"] = renderPathName(row.config.path);
  x["cull"] = cullModeName(row.config.cull);
  x["lod"] = row.config.lodLabel;
  x["lodErrorPixels"] = row.config.lod;
  x["idBits"] = row.idBits;
  x["shading"] = row.shading;
  x["raster"] = row.raster;
  if (row.shading == "classified") {
    x["materialsPresent"] = row.materialsPresent;
    x["tileMaterialPairs"] = row.classifiedTiles;
  }
  x["vertices"] = row.config.quantized ? "quantized" : "float";
  x["msaa"] = row.config.msaa;
  x["perSamplePixels"] = row.perSamplePixels;
  nlohmann::json passes = nlohmann::json::object();
  for (const auto& [name, v] : row.passMs) passes[name] = {{"median", v.first}, {"p95", v.second}};
  x["passMs"] = passes;
  x["frameMs"] = {{"median", row.frameMedian}, {"p95", row.frameP95}};
  x["gpuMs"] = {{"median", row.gpuMedian}, {"p95", row.gpuP95}};
  x["cpuRecordMs"] = {{"median", row.cpuMedian}};
  x["wallMs"] = {{"median", row.wallMedian}};
  x["trianglesDrawn"] = row.trianglesMedian;
  x["objectsDrawn"] = row.drawnMedian;
  if (row.trianglesPerCoveredPixel > 0) x["trianglesPerCoveredPixel"] = row.trianglesPerCoveredPixel;
  x["sceneBytes"] = row.sceneBytes;
  x["targetBytesPerPixel"] = row.targetBytesPerPixel;
  x["rasterWritesPerPixel"] = row.rasterWritesPerPixel;
  x["bytesWrittenPerPixel"] = row.bytesWrittenPerPixel;
  x["error"] = {{"psnrMean", dbJson(row.psnrMean)},
                {"psnrWorst", dbJson(row.psnrWorst)},
                {"maxAbs", row.maxAbs},
                {"meanAbs", row.meanAbs},
                {"differingFraction", row.differingFraction}};
  if (row.idMismatches) {
    x["idMismatches"] = *row.idMismatches;
    x["idPixelsCompared"] = row.idPixels;
  } else {
    x["idMismatches"] = "n/a";
  }
  x["reference"] = row.reference;
  x["pareto"] = row.pareto;
  return x;
}

nlohmann::json benchJson(const BenchCommand& c, const BenchResults& results, const std::string& deviceName,
                         uint32_t width, uint32_t height, const std::string& date) {
  nlohmann::json j;
  stampInvocation(j, deviceName);
  j["date"] = date;
  j["scene"] = c.scene;
  j["mesh"] = c.mesh;
  j["materials"] = c.materials;
  j["seed"] = c.seed;
  j["width"] = width;
  j["height"] = height;
  j["frames"] = c.frames;
  j["warmup"] = c.warmup;
  j["cameraPath"] = c.scene == "city"
                        ? "walk from the default camera along its avenue (min(150, 0.3 x bounds radius)), yaw +-0.6 rad"
                        : "90-degree arc around the bounds centre from the default camera, radius 100% -> 55%, "
                          "height +20% at mid-path";
  j["frameMs"] = "GPU time of all passes + CPU time to cull (forward) and record; medians over measured frames";
  j["psnrMean"] = "PSNR of the mean squared error over the measured frames (\"inf\": identical)";
  j["skipped"] = results.skipped;
  nlohmann::json sj = nlohmann::json::array();
  for (const BenchSceneInfo& s : results.scenes)
    sj.push_back({{"objects", s.objects},
                  {"sceneObjects", s.sceneObjects},
                  {"fullDetailTriangles", s.triangles},
                  {"reference", s.reference},
                  {"referenceReason", s.referenceReason},
                  {"referenceFrameMsMedian", s.referenceFrameMsMedian}});
  j["scenes"] = sj;
  nlohmann::json rj = nlohmann::json::array();
  for (const BenchRow& row : results.rows) rj.push_back(rowJson(row));
  j["rows"] = rj;
  return j;
}

std::string benchCsv(const BenchCommand& c, const std::vector<BenchRow>& rows) {
  // Every pass name, in first-seen order (CSV columns).
  std::vector<std::string> passNames;
  for (const BenchRow& row : rows)
    for (const auto& p : row.passMs)
      if (std::find(passNames.begin(), passNames.end(), p.first) == passNames.end()) passNames.push_back(p.first);
  auto passOf = [](const BenchRow& row, const std::string& name) -> const std::pair<double, double>* {
    for (const auto& p : row.passMs)
      if (p.first == name) return &p.second;
    return nullptr;
  };

  std::string csv =
      "scene,objects,path,cull,lod_px,id_bits,vertices,frames,frame_ms_median,frame_ms_p95,gpu_ms_median,gpu_ms_p95,"
      "cpu_record_ms_median,wall_ms_median,triangles_median,objects_drawn_median,scene_bytes,"
      "target_bytes_per_pixel,psnr_mean_db,psnr_worst_db,max_abs_error,mean_abs_error,differing_fraction,"
      "id_mismatches,reference,pareto";
  for (std::string n : passNames) {  // "depth pyramid" -> pass_depth_pyramid_ms_median
    std::replace(n.begin(), n.end(), ' ', '_');
    csv += fmt::format(",pass_{0}_ms_median,pass_{0}_ms_p95", n);
  }
  csv += ",raster_writes_per_pixel,bytes_written_per_pixel,msaa,per_sample_pixels,shading,raster,"
         "triangles_per_covered_pixel\n";  // appended: earlier columns fixed
  for (const BenchRow& row : rows) {
    csv += fmt::format("{},{},{},{},{},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.0f},{:.0f},{},{},{},{},{:.6f},{:.6f},{:.6f},{},{},{}",
                       c.scene.find(',') == std::string::npos ? c.scene : "\"" + c.scene + "\"", row.objects,
                       renderPathName(row.config.path), cullModeName(row.config.cull), row.config.lodLabel,
                       row.idBits, row.config.quantized ? "quantized" : "float", c.frames,
                       row.frameMedian, row.frameP95, row.gpuMedian, row.gpuP95, row.cpuMedian, row.wallMedian,
                       row.trianglesMedian, row.drawnMedian, row.sceneBytes, row.targetBytesPerPixel,
                       dbText(row.psnrMean), dbText(row.psnrWorst), row.maxAbs, row.meanAbs, row.differingFraction,
                       row.idMismatches ? fmt::format("{}", *row.idMismatches) : std::string("n/a"), row.reference,
                       row.pareto ? 1 : 0);
    for (const std::string& n : passNames) {
      const auto* p = passOf(row, n);
      csv += p ? fmt::format(",{:.4f},{:.4f}", p->first, p->second) : std::string(",,");
    }
    csv += fmt::format(",{:.4f},{:.2f},{},{:.0f},{},{},{}\n", row.rasterWritesPerPixel, row.bytesWrittenPerPixel,
                       row.config.msaa, row.perSamplePixels, row.shading, row.raster,
                       row.trianglesPerCoveredPixel > 0 ? fmt::format("{:.3f}", row.trianglesPerCoveredPixel) : "");
  }
  return csv;
}

std::string benchMarkdown(const BenchCommand& c, const BenchResults& results, const std::string& deviceName,
                          uint32_t width, uint32_t height, const std::string& date) {
  std::string md = fmt::format("`{}`\n\n", c.commandLine);
  md += fmt::format("{} ({} measured frames after {} warm-up along the camera path, {}x{}), {}. ", deviceName, c.frames,
                    c.warmup, width, height, date);
  md += "frame ms = GPU passes + CPU cull/record (median, p95); PSNR vs the reference: over all measured frames / worst "
        "frame; ID mism. = pixels whose decoded (object, triangle) differ from visbuf with no culling and no LOD; "
        "P = on the Pareto front (time vs PSNR; PSNRs within 0.1 dB count as equal); B/px = bytes per pixel of the "
        "path's targets / bytes written per pixel at the last camera (raster writes x bytes per fragment + resolve "
        "colour; clears not counted).\n\n";
  for (const BenchSceneInfo& s : results.scenes)
    md += fmt::format("- {} objects: {} objects, {} full-detail triangles; reference {} ({:.1f} ms a frame)\n",
                      objectsLabel(s.objects), s.sceneObjects, s.triangles, s.reference, s.referenceFrameMsMedian);
  md += "\n| objects | path | cull | LOD px | IDs | vertices | frame ms | p95 | GPU passes ms (median) | CPU rec ms | triangles | "
        "tri/px | drawn | scene MiB | B/px | PSNR dB | worst dB | max err | px > 1/255 | ID mism. | P |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const BenchRow& row : results.rows) {
    std::string passes;
    for (const auto& [name, v] : row.passMs) passes += fmt::format("{}{} {:.2f}", passes.empty() ? "" : ", ", name, v.first);
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {:.2f} | {:.2f} | {} | {:.2f} | {:.0f} | {} | {:.0f} | {:.1f} | {} / {:.1f} | {} | {} | "
                      "{:.4f} | {:.3f}% | {} | {} |\n",
                      objectsLabel(row.objects),
                      row.shading == "-" ? pathLabel(row.config)
                                         : fmt::format("{} ({}, {})", pathLabel(row.config), row.shading, row.raster),
                      cullModeName(row.config.cull), row.config.lodLabel, row.idBits, row.config.quantized ? "q16" : "float", row.frameMedian, row.frameP95, passes, row.cpuMedian, row.trianglesMedian,
                      row.trianglesPerCoveredPixel > 0 ? fmt::format("{:.2f}", row.trianglesPerCoveredPixel) : "-",
                      row.drawnMedian, row.sceneBytes / 1048576.0, row.targetBytesPerPixel, row.bytesWrittenPerPixel, dbText(row.psnrMean),
                      dbText(row.psnrWorst), row.maxAbs, 100.0 * row.differingFraction,
                      row.idMismatches ? fmt::format("{}", *row.idMismatches) : std::string("n/a"),
                      row.pareto ? "P" : "");
  }
  const nlohmann::json& skipped = results.skipped;
  if (!skipped.empty()) {
    md += "\nSkipped: ";
    for (size_t i = 0; i < skipped.size(); ++i)
      md += fmt::format("{}{}/{}: {}", i ? "; " : "", skipped[i]["path"].get<std::string>(),
                        skipped[i]["cull"].get<std::string>(), skipped[i]["reason"].get<std::string>());
    md += ".\n";
  }
  return md;
}

std::string benchSvg(const BenchCommand& c, const BenchResults& results, const std::string& deviceName,
                     uint32_t width, uint32_t height, const std::string& date) {
  std::vector<PlotPanel> panels;
  for (const BenchSceneInfo& s : results.scenes) {
    PlotPanel panel;
    panel.title = fmt::format("{}, {} objects, {}x{}, reference {}", c.scene, objectsLabel(s.objects), width, height,
                              s.reference);
    for (const BenchRow& row : results.rows)
      if (row.objects == s.objects)
        panel.points.push_back({renderPathName(row.config.path), cullModeName(row.config.cull), row.config.lodLabel,
                                row.frameMedian, row.psnrMean, row.pareto});
    panels.push_back(std::move(panel));
  }
  return renderBenchSvg(panels, fmt::format("visbuf bench: frame time against error ({})", deviceName),
                        fmt::format("{}   [{}]", c.commandLine, date));
}

}  // namespace

Status writeBenchReport(const BenchCommand& c, const BenchResults& results, const std::string& deviceName,
                        uint32_t width, uint32_t height) {
  const std::string date = utcNow();
  const std::filesystem::path out(c.output);
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"bench.csv", benchCsv(c, results.rows)},
           {"bench.md", benchMarkdown(c, results, deviceName, width, height, date)},
           {"bench.svg", benchSvg(c, results, deviceName, width, height, date)}}) {
    if (Status s = writeTextFile((out / name).string(), text); !s) return s;
  }
  return writeJsonFile((out / "bench.json").string(), benchJson(c, results, deviceName, width, height, date));
}

}  // namespace visbuf::tools
