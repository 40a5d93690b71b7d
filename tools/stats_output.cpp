#include "stats_output.h"

#include <cstdio>

#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include "visbuf/core/image_io.h"

namespace visbuf::tools {

std::string formatStats(const FrameStats& s) {
  std::string out;
  out += fmt::format("device        {}\n", s.device);
  out += fmt::format("path          {}  {}x{}\n", renderPathName(s.path), s.width, s.height);
  out += fmt::format("objects       {} tested, {} frustum-culled, {} occluded, {} sub-pixel, {} drawn ({} early + {} late)\n",
                     s.cull.objectsTested, s.cull.frustumCulled, s.cull.occlusionCulled, s.cull.subpixelCulled, s.cull.drawsRendered,
                     s.cull.drawsEarly, s.cull.drawsLate);
  if (s.cull.refineTested)
    out += fmt::format("refinement    {} objects tested again at a finer pyramid level, {} of them occluded there\n",
                       s.cull.refineTested, s.cull.refineOccluded);
  out += s.coveredPixels > 0
             ? fmt::format("triangles     {} drawn; {} covered pixels ({:.1f} %): {:.2f} triangles per covered pixel\n",
                           s.trianglesDrawn, s.coveredPixels, 100.0 * s.coveredPixels / (double(s.width) * s.height),
                           double(s.trianglesDrawn) / s.coveredPixels)
             : fmt::format("triangles     {} drawn\n", s.trianglesDrawn);
  if (s.cull.clusters.objects)
    out += fmt::format("clusters      {} objects drawn as clusters: {} clusters tested, {} outside the frustum, {} "
                       "back-facing, {} occluded or between pixel centres; {} draws; {} deferred by the early phase, "
                       "{} of them drawn late\n",
                       s.cull.clusters.objects, s.cull.clusters.tested, s.cull.clusters.frustumCulled,
                       s.cull.clusters.backfacing, s.cull.clusters.occluded, s.cull.clusters.draws,
                       s.cull.clusters.deferred, s.cull.clusters.recovered);
  if (s.sw.on)
    out += fmt::format("micro-raster  {} draws, {} triangles in compute; {} triangles it could not take; {}\n",
                       s.sw.draws, s.sw.triangles, s.sw.oversize,
                       s.sw.resolved ? "resolved by the pyramid and the shading" : "merged into the IDs and depth");
  if (s.transparent.draws)
    out += fmt::format("transparent   {} objects, {} triangles (sorted back to front)\n", s.transparent.draws,
                       s.transparent.triangles);
  std::string lods;
  for (size_t i = 0; i < s.cull.lodHistogram.size(); ++i) lods += fmt::format("{}{}", i ? " " : "", s.cull.lodHistogram[i]);
  out += fmt::format("lod histogram [{}]\n", lods);
  if (s.path != RenderPath::Forward) {
    if (s.cull.cullingFrozen) out += "culling       FROZEN: draw lists of an earlier frame\n";
    out += fmt::format("pyramid       {}\n",
                       s.pyramid.levels    ? fmt::format("{} levels", s.pyramid.levels)
                       : s.pyramid.skipped ? std::string("skipped (the last one hid nothing, or less than it cost)")
                                           : std::string("not built"));
    if (s.path == RenderPath::Visbuf) out += fmt::format("ids           {}\n", s.ids.describe());
    out += fmt::format("capacity      draws {} used of {}, overflow {}{}\n", s.cull.drawsRendered, s.cull.drawCapacity,
                       s.cull.drawOverflow, s.cull.drawOverflow ? "  (WARNING: visible objects were dropped)" : "");
  }
  if (s.skin.instances)
    out += fmt::format("skinning      {} instances, {} vertices, {} (poses {:.3f} ms CPU), {} bounds\n",
                       s.skin.instances, s.skin.vertices, s.skin.ran ? "re-skinned" : "pose unchanged: skipped",
                       s.skin.animationCpuMs, s.skin.bounds);
  out += s.lights.pointLights == 0 ? std::string("lights        directional only (no punctual lights: no light cull pass)\n")
         : s.lights.culled
             ? fmt::format("lights        {} punctual lights, tiles: {:.1f} mean / {} max per tile, overflow {} tiles{}\n",
                           s.lights.pointLights, s.lights.meanPerTile, s.lights.maxPerTile, s.lights.tileOverflow,
                           s.lights.tileOverflow ? fmt::format("  (WARNING: {} tile lights dropped)", s.lights.dropped) : "")
             : fmt::format("lights        {} punctual lights, every light at every pixel (no tiles)\n", s.lights.pointLights);
  if (s.path == RenderPath::Visbuf)
    out += s.shade.mode == ShadingMode::Classified
               ? fmt::format("shading       classified: {} of {} materials present, {} (tile, material) pairs for {} "
                             "8x8 tiles\n",
                             s.shade.materialsPresent, s.shade.materialPixels.size(), s.shade.classifiedTiles,
                             ((s.width + 7) / 8) * ((s.height + 7) / 8))
           : s.shade.mode == ShadingMode::Covered
               ? std::string("shading       covered (the ubershader over the pixels that show anything)\n")
               : std::string("shading       uber (one dispatch, every material)\n");
  out += fmt::format("frame graph   {} passes ({}), {} barriers ({} layout transitions){}\n", s.graph.passesRecorded.size(),
                     fmt::join(s.graph.passesRecorded, ", "), s.graph.barriers, s.graph.layoutTransitions,
                     s.graph.passesDropped.empty() ? std::string()
                                             : fmt::format("; dropped, nothing reads them: {}", fmt::join(s.graph.passesDropped, ", ")));
  for (const auto& [name, ms] : s.graph.passMs) out += fmt::format("gpu {:<14}{:9.3f} ms\n", name, ms);
  out += fmt::format("gpu total         {:9.3f} ms\n", s.gpuMs);
  out += fmt::format("cpu record    {:9.3f} ms   wall {:9.3f} ms\n", s.cpuRecordMs, s.wallMs);
  out += fmt::format("memory        scene {:.1f} MiB, targets {} B/pixel\n", s.sceneBytes / 1048576.0,
                     s.targetBytesPerPixel);
  if (s.textureClasses)
    out += fmt::format("textures      {} classes, {:.1f} MiB on the GPU{}\n", s.textureClasses, s.textureBytes / 1048576.0,
                       s.texturesDecompressed
                           ? fmt::format("; {} BC classes decompressed to RGBA8 at load (the device lacks "
                                         "textureCompressionBC)",
                                         s.texturesDecompressed)
                           : std::string());
  if (s.msaaSamples > 1)
    out += s.path == RenderPath::Visbuf
               ? fmt::format("msaa          {}x: {} pixels ({:.2f}%) shaded per distinct sample ID\n", s.msaaSamples,
                             s.shade.perSamplePixels, 100.0 * s.shade.perSamplePixels / (double(s.width) * s.height))
               : fmt::format("msaa          {}x, hardware resolve\n", s.msaaSamples);
  if (s.rasterWritesPerPixel > 0.0)
    out += fmt::format("bandwidth     {:.2f} raster writes/pixel x {} B + resolve = {:.1f} B written/pixel\n",
                       s.rasterWritesPerPixel, s.rasterBytesPerFragment, s.bytesWrittenPerPixel);
  return out;
}

nlohmann::json statsToJson(const FrameStats& s) {
  nlohmann::json j;
  j["device"] = s.device;
  j["path"] = renderPathName(s.path);
  j["width"] = s.width;
  j["height"] = s.height;
  j["objects"] = s.objects;
  j["objectsTested"] = s.cull.objectsTested;
  j["frustumCulled"] = s.cull.frustumCulled;
  j["occlusionCulled"] = s.cull.occlusionCulled;
  j["subpixelCulled"] = s.cull.subpixelCulled;
  j["refineTested"] = s.cull.refineTested;
  j["refineOccluded"] = s.cull.refineOccluded;
  j["drawsEarly"] = s.cull.drawsEarly;
  j["drawsLate"] = s.cull.drawsLate;
  j["cullingFrozen"] = s.cull.cullingFrozen;
  j["pyramidLevels"] = s.pyramid.levels;
  j["pyramidSkipped"] = s.pyramid.skipped;
  j["drawsAppended"] = s.cull.drawsAppended;
  j["drawsRendered"] = s.cull.drawsRendered;
  j["drawCapacity"] = s.cull.drawCapacity;
  j["drawOverflow"] = s.cull.drawOverflow;
  j["trianglesDrawn"] = s.trianglesDrawn;
  j["coveredPixels"] = s.coveredPixels;
  if (s.coveredPixels > 0) j["trianglesPerCoveredPixel"] = double(s.trianglesDrawn) / s.coveredPixels;
  j["swRaster"] = {{"on", s.sw.on}, {"draws", s.sw.draws}, {"triangles", s.sw.triangles}, {"oversize", s.sw.oversize},
                  {"resolved", s.sw.resolved}};
  const CullStats::Clusters& c = s.cull.clusters;
  j["clusters"] = {{"objects", c.objects},       {"tested", c.tested},     {"frustumCulled", c.frustumCulled},
                   {"backfacing", c.backfacing}, {"occluded", c.occluded}, {"draws", c.draws},
                   {"deferred", c.deferred},     {"recovered", c.recovered}};
  j["transparentDraws"] = s.transparent.draws;
  j["transparentTriangles"] = s.transparent.triangles;
  j["lodHistogram"] = s.cull.lodHistogram;
  j["ids"] = {{"wide", s.ids.wide}, {"triangleBits", s.ids.triangleBits}, {"slotBits", s.ids.slotBits},
              {"description", s.ids.describe()}};
  nlohmann::json passes = nlohmann::json::object();
  for (const auto& [name, ms] : s.graph.passMs) passes[name] = ms;
  j["passMs"] = passes;
  j["frameGraph"] = {{"passes", s.graph.passesRecorded}, {"dropped", s.graph.passesDropped}, {"barriers", s.graph.barriers},
                     {"layoutTransitions", s.graph.layoutTransitions}};
  j["gpuMs"] = s.gpuMs;
  j["cpuRecordMs"] = s.cpuRecordMs;
  j["wallMs"] = s.wallMs;
  j["skinnedInstances"] = s.skin.instances;
  j["skinnedVertices"] = s.skin.vertices;
  j["skinned"] = s.skin.ran;
  j["animationCpuMs"] = s.skin.animationCpuMs;
  j["skinBounds"] = s.skin.bounds;
  j["lights"] = {{"pointLights", s.lights.pointLights}, {"culled", s.lights.culled}, {"tileOverflow", s.lights.tileOverflow},
                 {"dropped", s.lights.dropped}, {"maxPerTile", s.lights.maxPerTile},
                 {"meanPerTile", s.lights.meanPerTile}, {"bytes", s.lights.bytes}};
  if (s.path == RenderPath::Visbuf) {
    j["shading"] = shadingModeName(s.shade.mode);
    if (s.shade.mode == ShadingMode::Classified)
      j["classification"] = {{"materialsPresent", s.shade.materialsPresent}, {"tileMaterialPairs", s.shade.classifiedTiles},
                             {"materialTiles", s.shade.materialTiles}, {"materialPixels", s.shade.materialPixels}};
  }
  j["sceneBytes"] = s.sceneBytes;
  j["objectsUpdated"] = s.upload.objects;
  j["uploadedBytes"] = s.upload.bytes;
  j["frameIndex"] = s.frameIndex;
  j["textures"] = {{"classes", s.textureClasses}, {"bytes", s.textureBytes}, {"decompressed", s.texturesDecompressed}};
  j["targetBytesPerPixel"] = s.targetBytesPerPixel;
  j["msaa"] = {{"samples", s.msaaSamples}, {"perSamplePixels", s.shade.perSamplePixels}};
  j["rasterBytesPerFragment"] = s.rasterBytesPerFragment;
  if (s.rasterWritesPerPixel > 0.0) {
    j["rasterWritesPerPixel"] = s.rasterWritesPerPixel;
    j["bytesWrittenPerPixel"] = s.bytesWrittenPerPixel;
  }
  return j;
}

nlohmann::json motionFrameJson(const SceneMotionFrame& m, const FrameStats& s) {
  return {{"frame", s.frameIndex},
          {"moved", m.moved},
          {"added", m.added},
          {"removed", m.removed},
          {"hidden", m.hidden},
          {"shown", m.shown},
          {"objectsUpdated", s.upload.objects},
          {"uploadedBytes", s.upload.bytes},
          {"objectsTested", s.cull.objectsTested},
          {"frustumCulled", s.cull.frustumCulled},
          {"occlusionCulled", s.cull.occlusionCulled},
          {"subpixelCulled", s.cull.subpixelCulled},
          {"drawsEarly", s.cull.drawsEarly},
          {"drawsLate", s.cull.drawsLate},
          {"drawsRendered", s.cull.drawsRendered},
          {"trianglesDrawn", s.trianglesDrawn},
          {"coveredPixels", s.coveredPixels},
          {"gpuMs", s.gpuMs},
          {"cpuRecordMs", s.cpuRecordMs}};
}

std::string formatMotion(const nlohmann::json& perFrame, uint32_t movingObjects) {
  if (perFrame.empty()) return {};
  uint64_t bytes = 0, updated = 0, added = 0, removed = 0, hidden = 0;
  for (const nlohmann::json& f : perFrame) {
    bytes += f["uploadedBytes"].get<uint64_t>();
    updated += f["objectsUpdated"].get<uint64_t>();
    added += f["added"].get<uint64_t>();
    removed += f["removed"].get<uint64_t>();
    hidden += f["hidden"].get<uint64_t>();
  }
  const double n = double(perFrame.size());
  return fmt::format("scene changes {} moving objects; per frame (mean of {}): {:.0f} added, {:.0f} removed, {:.0f} "
                     "hidden, {:.0f} records = {:.1f} KiB uploaded\n",
                     movingObjects, perFrame.size(), double(added) / n, double(removed) / n, double(hidden) / n,
                     double(updated) / n, double(bytes) / n / 1024.0);
}

Status writeTextFile(const std::string& path, const std::string& text) {
  const std::string tmp = path + fmt::format(".tmp{}", getpid());
  {
    // "x": created new (O_EXCL), never an existing file truncated through its name or a link.
    std::FILE* f = std::fopen(tmp.c_str(), "wbx");
    if (!f) return makeError(ErrorCode::IoError, fmt::format("{}: cannot create the temporary file for writing", path));
    const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    if (std::fclose(f) != 0 || !written) {
      std::remove(tmp.c_str());
      return makeError(ErrorCode::IoError, fmt::format("{}: write failed", path));
    }
  }
  return commitFile(tmp, path);
}

Status writeJsonFile(const std::string& path, const nlohmann::json& json) {
  return writeTextFile(path, json.dump(2) + "\n");
}

}  // namespace visbuf::tools
