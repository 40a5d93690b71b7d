// The stress cases on input and limits: malformed scenes and glTF files, draw capacity below the visible set,
// and millions of objects. Every bound is stated in StressCase::bound and checked here.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "stress_scene.h"
#include "visbuf/asset/load_scene.h"
#include "visbuf/scene/generate.h"

namespace visbuf::tools::stress {

// ---- bad input ----------------------------------------------------------------------------------------

// Every colour channel finite and in [0, 1] (the colour target is cleared to the background, shading
// clamps nothing: a NaN or an out-of-range value would be garbage).
bool colorsSane(const FrameResult& f) {
  for (float v : f.color)
    if (!std::isfinite(v) || v < 0.0f || v > 1.0f) return false;
  return true;
}

StressCase badInput(const StressContext& ctx) {
  StressCase c{"bad-input",
               "NaN/Inf transforms, zero-scale objects, NaN vertices, out-of-range indices, degenerate triangles, "
               "and the malformed glTF files in assets/AssimpBadData",
               "each is rejected with a message naming the culprit, or repaired/rendered with only finite colours "
               "in [0,1]; never a crash",
               {}};
  FieldParams p;
  p.objects = 50;
  p.extent = 10.0;
  p.mesh = makeTorusKnot(32, 8);
  auto base = makeFieldScene(p);
  if (!base) return c.rows.push_back(errorRow("field", base.error())), c;
  auto rejected = [&](const std::string& label, const Scene& s, const std::string& expect) {
    auto r = Renderer::create(ctx.device, s, {.width = 32, .height = 32});
    const std::string msg = r ? std::string("accepted") : r.error().message;
    c.rows.push_back({{{"case", label},
                       {"outcome", r ? "accepted" : "rejected"},
                       {"message", msg},
                       {"pass", !r && msg.find(expect) != std::string::npos}}});
  };
  {
    Scene s = *base;
    s.objects[7].transform[3][1] = NAN;
    rejected("NaN translation", s, "object 7");
  }
  {
    Scene s = *base;
    s.objects[3].transform[0][0] = INFINITY;
    rejected("Inf in the 3x3 part", s, "object 3");
  }
  {
    Scene s = *base;
    s.objects[5].transform = glm::scale(glm::dmat4(1.0), glm::dvec3(0.0));
    rejected("zero-scale object", s, "zero-scale");
  }
  auto buildRejected = [&](const std::string& label, MeshSource m, const std::string& expect) {
    auto r = buildMesh(m);
    const std::string msg = r ? std::string("accepted") : r.error().message;
    c.rows.push_back({{{"case", label},
                       {"outcome", r ? "accepted" : "rejected"},
                       {"message", msg},
                       {"pass", !r && msg.find(expect) != std::string::npos}}});
  };
  {
    MeshSource m = makeBox();
    m.positions[2].y = NAN;
    buildRejected("NaN vertex position", m, "vertex 2");
  }
  {
    MeshSource m = makeBox();
    m.indices[4] = uint32_t(m.positions.size());
    buildRejected("index out of range", m, "index");
  }
  {  // zero-area triangles (a repeated vertex, collinear vertices) among real ones
    std::vector<glm::vec3> tris = {{-1, -1, -3}, {1, -1, -3}, {0, 1, -3},      // real
                                   {0, 0, -2},   {0, 0, -2}, {1, 1, -2},       // repeated vertex
                                   {-1, 0, -2},  {0, 0, -2}, {1, 0, -2}};      // collinear
    MeshSource m;
    m.name = "degenerate";
    for (const glm::vec3& v : tris) {
      m.positions.push_back(v);
      m.normals.push_back({0, 0, 1});
      m.indices.push_back(uint32_t(m.indices.size()));
    }
    auto s = sceneOf("degenerate", {m}, {{0u, glm::dmat4(1.0)}}, kAtOrigin);
    if (!s) {
      c.rows.push_back({{{"case", "degenerate triangles"}, {"outcome", "rejected"}, {"message", s.error().message},
                         {"pass", !s.error().message.empty()}}});
    } else {
      auto r = renderOnce(ctx.device, *s, kAtOrigin, 64, 64, false);
      const bool ok = r && colorsSane(r->frame) && coveredPixels(r->frame) > 0;
      c.rows.push_back({{{"case", "degenerate triangles"},
                         {"outcome", r ? fmt::format("rendered, {} px covered", coveredPixels(r->frame))
                                       : r.error().message},
                         {"message", ""},
                         {"pass", ok}}});
    }
  }
  const std::filesystem::path bad = std::filesystem::path(ctx.assetsDir) / "AssimpBadData";
  std::error_code ec;
  if (ctx.assetsDir.empty() || !std::filesystem::is_directory(bad, ec)) return c;
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::recursive_directory_iterator(bad, ec)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".gltf" || ext == ".glb") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    const std::string label = "glTF " + f.filename().string();
    // As `render --scene FILE` loads it (load_scene.h: import, mesh build, textures), at the default budgets.
    auto loaded = visbuf::loadScene(f);
    if (!loaded) {
      c.rows.push_back({{{"case", label}, {"outcome", "rejected"}, {"message", loaded.error().message},
                         {"pass", !loaded.error().message.empty()}}});
      continue;
    }
    const Scene* scene = &loaded->scene;
    auto r = renderOnce(ctx.device, *scene, scene->defaultCamera, 64, 64, false);
    const std::string outcome = r ? "rendered" : "rejected at upload";
    c.rows.push_back({{{"case", label}, {"outcome", outcome}, {"message", r ? "" : r.error().message},
                       {"pass", r ? colorsSane(r->frame) : !r.error().message.empty()}}});
  }
  return c;
}

// ---- capacity ------------------------------------------------------------------------------------------

StressCase capacity(const StressContext& ctx) {
  StressCase c{"capacity",
               "draw capacity far below the visible set (every cull mode), and the 64-bit ID target forced where "
               "32 bits fit",
               "overflow reported exactly (appended - rendered) and never silent; the image degrades predictably: "
               "only dropped objects vanish (every pixel whose reference object was drawn shows the reference's "
               "object and triangle), no invalid ID; wide IDs give the narrow image exactly",
               {}};
  FieldParams p;
  p.objects = ctx.reduced ? 1000 : 20000;
  p.extent = ctx.reduced ? 40.0 : 120.0;
  p.mesh = makeTorusKnot(48, 12);
  auto s = makeFieldScene(p);
  if (!s) return c.rows.push_back(errorRow("field", s.error())), c;
  const uint32_t w = ctx.reduced ? 200 : 640, h = ctx.reduced ? 140 : 400;
  auto ref = renderOnce(ctx.device, *s, s->defaultCamera, w, h, false);
  if (!ref) return c.rows.push_back(errorRow("reference", ref.error())), c;
  const uint32_t cap = std::max<uint32_t>(1, ref->frame.stats.cull.drawsRendered / 10);
  // A capped draw list never uses the micro-raster (FrameOptions::swRaster): the capped frames are compared
  // with a reference from the hardware raster alone, so that a pixel where the two rasterisers break a tie
  // differently (about 1 pixel in 1 of 6 runs, on whichever objects survive the cap) is not counted as wrong.
  auto refHw = renderOnce(ctx.device, *s, s->defaultCamera, w, h, false, {}, SwRasterMode::Off);
  if (!refHw) return c.rows.push_back(errorRow("reference (hardware raster)", refHw.error())), c;
  for (CullMode mode : {CullMode::None, CullMode::Frustum, CullMode::Occlusion}) {
    const std::string label = fmt::format("capacity {} ({}), cull {}", cap, "10% of the visible set",
                                          cullModeName(mode));
    auto r = Renderer::create(ctx.device, *s, {.width = w, .height = h, .drawCapacity = cap});
    if (!r) {
      c.rows.push_back(errorRow(label, r.error()));
      continue;
    }
    FrameOptions fo;
    fo.readIds = fo.readDraws = true;
    fo.lodErrorPixels = 0.0f;
    fo.cull = mode;
    auto f = (*r)->renderFrame(s->defaultCamera, fo);
    if (!f) {
      c.rows.push_back(errorRow(label, f.error()));
      continue;
    }
    std::vector<bool> drawn(s->objects.size(), false);
    for (uint32_t o : f->drawnObjects) drawn[o] = true;
    size_t invalid = 0, wrong = 0, vanished = 0;
    for (size_t i = 0; i < size_t(w) * h; ++i) {
      const uint32_t got = f->ids[2 * i], want = refHw->frame.ids[2 * i];
      if (got == 0xFFFFFFFFu || (got != 0 && !drawn[got - 1])) ++invalid;
      if (want != 0 && drawn[want - 1] && (got != want || f->ids[2 * i + 1] != refHw->frame.ids[2 * i + 1])) ++wrong;
      if (want != 0 && !drawn[want - 1]) ++vanished;
    }
    const FrameStats& st = f->stats;
    const bool exact = st.cull.drawOverflow == st.cull.drawsAppended - st.cull.drawsRendered && st.cull.drawOverflow > 0;
    c.rows.push_back({{{"case", label},
                       {"appended", st.cull.drawsAppended},
                       {"rendered", st.cull.drawsRendered},
                       {"overflow", st.cull.drawOverflow},
                       {"pixels_of_dropped_objects", vanished},
                       {"wrong_pixels", wrong},
                       {"invalid_ids", invalid},
                       {"pass", exact && wrong == 0 && invalid == 0}}});
  }
  auto wide = renderOnce(ctx.device, *s, s->defaultCamera, w, h, false, {.forceWideIds = true});
  if (!wide) return c.rows.push_back(errorRow("wide IDs", wide.error())), c;
  size_t differ = 0;
  for (size_t i = 0; i < wide->frame.ids.size(); ++i) differ += wide->frame.ids[i] != ref->frame.ids[i];
  c.rows.push_back({{{"case", "64-bit IDs forced vs " + ref->renderer->idEncoding().describe()},
                     {"differing_ids", differ},
                     {"pass", differ == 0 && wide->renderer->idEncoding().wide}}});
  return c;
}

// ---- scale -----------------------------------------------------------------------------------------------

constexpr double kMaxBytesPerObject = 512.0;  // GPU memory of the scene mirror per object (mesh pool excluded)

StressCase scale(const StressContext& ctx) {
  StressCase c{"scale",
               "the field layout (torus knot, 28,800 triangles, default camera, occlusion culling, LOD 1 px) at 1M "
               "and 4M objects (reduced: 10k and 100k): frame time, triangles, GPU memory per object",
               fmt::format("frames complete with no draw overflow and triangles drawn; scene memory beyond the "
                           "mesh pool <= {:.0f} bytes per object (the renderer adds its draw lists and visibility history, also "
                           "per object, reported beside it)",
                           kMaxBytesPerObject),
               {}};
  const std::vector<uint32_t> counts =
      ctx.reduced ? std::vector<uint32_t>{10'000, 100'000} : std::vector<uint32_t>{1'000'000, 4'000'000};
  const uint32_t w = ctx.reduced ? 320 : 1024, h = ctx.reduced ? 240 : 768;
  for (uint32_t n : counts) {
    const std::string label = fmt::format("{} objects", n);
    FieldParams p;
    p.objects = n;
    auto s = makeFieldScene(p);
    if (!s) {
      c.rows.push_back(errorRow(label, s.error()));
      continue;
    }
    auto r = Renderer::create(ctx.device, *s, {.width = w, .height = h});
    if (!r) {
      c.rows.push_back(errorRow(label, r.error()));
      continue;
    }
    FrameOptions fo;
    fo.readColor = false;
    std::vector<double> ms;
    FrameStats last;
    for (int i = 0; i < 3; ++i) {  // frame 0: warm-up (empty history); median of the other two = their mean
      auto f = (*r)->renderFrame(s->defaultCamera, fo);
      if (!f) {
        c.rows.push_back(errorRow(label, f.error()));
        break;
      }
      if (i > 0) ms.push_back(f->stats.gpuMs + f->stats.cpuRecordMs);
      last = f->stats;
    }
    if (ms.size() != 2) continue;
    uint64_t meshBytes = 0;
    for (const Mesh& m : s->meshes)
      meshBytes += m.vertices.size() * sizeof(gpu::Vertex) + m.indices.size() * sizeof(uint32_t);
    const double perObject = double(last.sceneBytes > meshBytes ? last.sceneBytes - meshBytes : 0) / n;
    c.rows.push_back({{{"case", label},
                       {"size", fmt::format("{}x{}", w, h)},
                       {"frame_ms", 0.5 * (ms[0] + ms[1])},
                       {"drawn", last.cull.drawsRendered},
                       {"triangles", last.trianglesDrawn},
                       {"scene_MiB", last.sceneBytes / 1048576.0},
                       {"bytes_per_object", perObject},
                       {"renderer_bytes_per_object", 2 * sizeof(gpu::DrawCommand) + sizeof(uint32_t)},
                       {"pass", last.cull.drawOverflow == 0 && last.trianglesDrawn > 0 && perObject <= kMaxBytesPerObject}}});
  }
  return c;
}

}  // namespace visbuf::tools::stress
