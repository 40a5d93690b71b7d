#include "stats_output.h"

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
                     s.objectsTested, s.frustumCulled, s.occlusionCulled, s.subpixelCulled, s.drawsRendered,
                     s.drawsEarly, s.drawsLate);
  if (s.refineTested)
    out += fmt::format("refinement    {} objects tested again at a finer pyramid level, {} of them occluded there\n",
                       s.refineTested, s.refineOccluded);
  out += s.coveredPixels > 0
             ? fmt::format("triangles     {} drawn; {} covered pixels ({:.1f} %): {:.2f} triangles per covered pixel\n",
                           s.trianglesDrawn, s.coveredPixels, 100.0 * s.coveredPixels / (double(s.width) * s.height),
                           double(s.trianglesDrawn) / s.coveredPixels)
             : fmt::format("triangles     {} drawn\n", s.trianglesDrawn);
  if (s.swRaster)
    out += fmt::format("micro-raster  {} draws, {} triangles in compute; {} triangles it could not take\n", s.swDraws,
                       s.swTriangles, s.swOversize);
  if (s.transparentDraws)
    out += fmt::format("transparent   {} objects, {} triangles (sorted back to front)\n", s.transparentDraws,
                       s.transparentTriangles);
  std::string lods;
  for (size_t i = 0; i < s.lodHistogram.size(); ++i) lods += fmt::format("{}{}", i ? " " : "", s.lodHistogram[i]);
  out += fmt::format("lod histogram [{}]\n", lods);
  if (s.path != RenderPath::Forward) {
    if (s.cullingFrozen) out += "culling       FROZEN: draw lists of an earlier frame\n";
    out += fmt::format("pyramid       {}\n", s.pyramidLevels  ? fmt::format("{} levels", s.pyramidLevels)
                                            : s.pyramidSkipped ? std::string("skipped (the last one hid nothing)")
                                                               : std::string("not built"));
    if (s.path == RenderPath::Visbuf) out += fmt::format("ids           {}\n", s.ids.describe());
    out += fmt::format("capacity      draws {} used of {}, overflow {}{}\n", s.drawsRendered, s.drawCapacity,
                       s.drawOverflow, s.drawOverflow ? "  (WARNING: visible objects were dropped)" : "");
  }
  if (s.skinnedInstances)
    out += fmt::format("skinning      {} instances, {} vertices, {} (poses {:.3f} ms CPU), {} bounds\n",
                       s.skinnedInstances, s.skinnedVertices, s.skinned ? "re-skinned" : "pose unchanged: skipped",
                       s.animationCpuMs, s.skinBounds);
  out += s.pointLights == 0 ? std::string("lights        directional only (no punctual lights: no light cull pass)\n")
         : s.lightsCulled
             ? fmt::format("lights        {} punctual lights, tiles: {:.1f} mean / {} max per tile, overflow {} tiles{}\n",
                           s.pointLights, s.meanLightsPerTile, s.maxLightsPerTile, s.lightTileOverflow,
                           s.lightTileOverflow ? fmt::format("  (WARNING: {} tile lights dropped)", s.lightsDropped) : "")
             : fmt::format("lights        {} punctual lights, every light at every pixel (no tiles)\n", s.pointLights);
  if (s.path == RenderPath::Visbuf)
    out += s.shading == ShadingMode::Classified
               ? fmt::format("shading       classified: {} of {} materials present, {} (tile, material) pairs for {} "
                             "8x8 tiles\n",
                             s.materialsPresent, s.materialPixels.size(), s.classifiedTiles,
                             ((s.width + 7) / 8) * ((s.height + 7) / 8))
           : s.shading == ShadingMode::Covered
               ? std::string("shading       covered (the ubershader over the 8x8 tiles that show anything)\n")
               : std::string("shading       uber (one dispatch, every material)\n");
  out += fmt::format("frame graph   {} passes ({}), {} barriers ({} layout transitions){}\n", s.passesRecorded.size(),
                     fmt::join(s.passesRecorded, ", "), s.barriers, s.layoutTransitions,
                     s.passesDropped.empty() ? std::string()
                                             : fmt::format("; dropped, nothing reads them: {}", fmt::join(s.passesDropped, ", ")));
  for (const auto& [name, ms] : s.passMs) out += fmt::format("gpu {:<14}{:9.3f} ms\n", name, ms);
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
                             s.perSamplePixels, 100.0 * s.perSamplePixels / (double(s.width) * s.height))
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
  j["objectsTested"] = s.objectsTested;
  j["frustumCulled"] = s.frustumCulled;
  j["occlusionCulled"] = s.occlusionCulled;
  j["subpixelCulled"] = s.subpixelCulled;
  j["refineTested"] = s.refineTested;
  j["refineOccluded"] = s.refineOccluded;
  j["drawsEarly"] = s.drawsEarly;
  j["drawsLate"] = s.drawsLate;
  j["cullingFrozen"] = s.cullingFrozen;
  j["pyramidLevels"] = s.pyramidLevels;
  j["pyramidSkipped"] = s.pyramidSkipped;
  j["drawsAppended"] = s.drawsAppended;
  j["drawsRendered"] = s.drawsRendered;
  j["drawCapacity"] = s.drawCapacity;
  j["drawOverflow"] = s.drawOverflow;
  j["trianglesDrawn"] = s.trianglesDrawn;
  j["coveredPixels"] = s.coveredPixels;
  if (s.coveredPixels > 0) j["trianglesPerCoveredPixel"] = double(s.trianglesDrawn) / s.coveredPixels;
  j["swRaster"] = {{"on", s.swRaster}, {"draws", s.swDraws}, {"triangles", s.swTriangles}, {"oversize", s.swOversize}};
  j["transparentDraws"] = s.transparentDraws;
  j["transparentTriangles"] = s.transparentTriangles;
  j["lodHistogram"] = s.lodHistogram;
  j["ids"] = {{"wide", s.ids.wide}, {"triangleBits", s.ids.triangleBits}, {"slotBits", s.ids.slotBits},
              {"description", s.ids.describe()}};
  nlohmann::json passes = nlohmann::json::object();
  for (const auto& [name, ms] : s.passMs) passes[name] = ms;
  j["passMs"] = passes;
  j["frameGraph"] = {{"passes", s.passesRecorded}, {"dropped", s.passesDropped}, {"barriers", s.barriers},
                     {"layoutTransitions", s.layoutTransitions}};
  j["gpuMs"] = s.gpuMs;
  j["cpuRecordMs"] = s.cpuRecordMs;
  j["wallMs"] = s.wallMs;
  j["skinnedInstances"] = s.skinnedInstances;
  j["skinnedVertices"] = s.skinnedVertices;
  j["skinned"] = s.skinned;
  j["animationCpuMs"] = s.animationCpuMs;
  j["skinBounds"] = s.skinBounds;
  j["lights"] = {{"pointLights", s.pointLights}, {"culled", s.lightsCulled}, {"tileOverflow", s.lightTileOverflow},
                 {"dropped", s.lightsDropped}, {"maxPerTile", s.maxLightsPerTile},
                 {"meanPerTile", s.meanLightsPerTile}, {"bytes", s.lightBytes}};
  if (s.path == RenderPath::Visbuf) {
    j["shading"] = shadingModeName(s.shading);
    if (s.shading == ShadingMode::Classified)
      j["classification"] = {{"materialsPresent", s.materialsPresent}, {"tileMaterialPairs", s.classifiedTiles},
                             {"materialTiles", s.materialTiles}, {"materialPixels", s.materialPixels}};
  }
  j["sceneBytes"] = s.sceneBytes;
  j["objectsUpdated"] = s.objectsUpdated;
  j["uploadedBytes"] = s.uploadedBytes;
  j["frameIndex"] = s.frameIndex;
  j["textures"] = {{"classes", s.textureClasses}, {"bytes", s.textureBytes}, {"decompressed", s.texturesDecompressed}};
  j["targetBytesPerPixel"] = s.targetBytesPerPixel;
  j["msaa"] = {{"samples", s.msaaSamples}, {"perSamplePixels", s.perSamplePixels}};
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
          {"objectsUpdated", s.objectsUpdated},
          {"uploadedBytes", s.uploadedBytes},
          {"objectsTested", s.objectsTested},
          {"frustumCulled", s.frustumCulled},
          {"occlusionCulled", s.occlusionCulled},
          {"subpixelCulled", s.subpixelCulled},
          {"drawsEarly", s.drawsEarly},
          {"drawsLate", s.drawsLate},
          {"drawsRendered", s.drawsRendered},
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
    std::ofstream f(tmp, std::ios::binary);
    if (!f) return makeError(ErrorCode::IoError, fmt::format("{}: cannot open for writing", path));
    f << text;
    if (!f.flush()) return makeError(ErrorCode::IoError, fmt::format("{}: write failed", path));
  }
  return commitFile(tmp, path);
}

Status writeJsonFile(const std::string& path, const nlohmann::json& json) {
  return writeTextFile(path, json.dump(2) + "\n");
}

}  // namespace visbuf::tools
