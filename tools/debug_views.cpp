#include "debug_views.h"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <unordered_map>

#include <fmt/format.h>

#include "visbuf/render/frame_math.h"

namespace visbuf::tools {

namespace {

// A stable, well-spread colour per integer (splitmix64 finaliser).
glm::vec3 hashColor(uint64_t v) {
  v += 0x9E3779B97F4A7C15ull;
  v = (v ^ (v >> 30)) * 0xBF58476D1CE4E5B9ull;
  v = (v ^ (v >> 27)) * 0x94D049BB133111EBull;
  v ^= v >> 31;
  return glm::vec3(float(v & 0xFF), float((v >> 8) & 0xFF), float((v >> 16) & 0xFF)) / 255.0f * 0.8f + 0.2f;
}

// Blue (0) .. red (max) ramp.
glm::vec3 ramp(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  return glm::vec3(std::clamp(1.5f - std::abs(4.0f * t - 3.0f), 0.0f, 1.0f),
                   std::clamp(1.5f - std::abs(4.0f * t - 2.0f), 0.0f, 1.0f),
                   std::clamp(1.5f - std::abs(4.0f * t - 1.0f), 0.0f, 1.0f));
}

void put(std::vector<float>& img, size_t pixel, glm::vec3 c) {
  img[pixel * 4 + 0] = c.r;
  img[pixel * 4 + 1] = c.g;
  img[pixel * 4 + 2] = c.b;
  img[pixel * 4 + 3] = 1.0f;
}

}  // namespace

const std::vector<std::string>& debugViewNames() {
  static const std::vector<std::string> names = {"shaded", "objects", "triangles", "lod", "culled", "pyramid", "overdraw"};
  return names;
}

void prepareViewOptions(const std::string& view, FrameOptions& o) {
  if (view == "objects" || view == "triangles" || view == "lod") o.readIds = true;
  if (view == "lod" || view == "culled") o.readDraws = true;
  if (view == "culled") o.readColor = true;
  if (view == "pyramid") o.readPyramid = true;
  if (view == "overdraw") o.countOverdraw = true;
}

Result<std::vector<float>> buildDebugView(const std::string& view, const FrameResult& f, const Scene& scene,
                                          const Camera& camera, int pyramidLevel) {
  const size_t pixels = size_t(f.width) * f.height;
  std::vector<float> img(pixels * 4, 0.0f);
  for (size_t p = 0; p < pixels; ++p) put(img, p, glm::vec3(0.05f));
  if (view == "objects" || view == "triangles" || view == "lod") {
    if (f.ids.size() != pixels * 2)
      return makeError(ErrorCode::InvalidArgument, fmt::format("--view {} needs the visbuf path", view));
    std::unordered_map<uint32_t, uint32_t> lodOf;
    uint32_t maxLod = 1;
    for (size_t i = 0; i < f.drawnObjects.size() && i < f.drawnLods.size(); ++i) {
      lodOf[f.drawnObjects[i]] = f.drawnLods[i];
      maxLod = std::max(maxLod, f.drawnLods[i]);
    }
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t object = f.ids[2 * p], tri = f.ids[2 * p + 1];
      if (object == 0) continue;
      if (view == "objects") put(img, p, hashColor(object));
      else if (view == "triangles") put(img, p, hashColor((uint64_t(object) << 32) | tri));
      else put(img, p, ramp(float(lodOf[object - 1]) / float(maxLod)));
    }
    return img;
  }
  if (view == "overdraw") {
    // Raster writes per pixel (fragments passing the depth test when they ran): black 0, then a ramp
    // from blue (1) to red (>= 8). The mean over covered pixels goes to stdout.
    if (f.overdraw.size() != pixels) return makeError(ErrorCode::InvalidArgument, "--view overdraw: no counts read back");
    uint64_t sum = 0, covered = 0;
    for (size_t p = 0; p < pixels; ++p) {
      const uint32_t n = f.overdraw[p];
      if (n == 0) continue;
      sum += n;
      ++covered;
      put(img, p, ramp(float(n - 1) / 7.0f));
    }
    std::printf("overdraw      %.2f raster writes per covered pixel (%llu pixels)\n",
                covered ? double(sum) / double(covered) : 0.0, (unsigned long long)covered);
    return img;
  }
  if (view == "pyramid") {
    if (f.pyramid.empty()) return makeError(ErrorCode::InvalidArgument, "--view pyramid needs --cull occlusion");
    if (pyramidLevel < 0 || size_t(pyramidLevel) >= f.pyramid.size())
      return makeError(ErrorCode::InvalidArgument,
                       fmt::format("--pyramid-level {}: this frame's pyramid has levels 0..{}", pyramidLevel, f.pyramid.size() - 1));
    const FrameResult::PyramidLevel& level = f.pyramid[size_t(pyramidLevel)];
    // Each texel covers 2^level pixels per side; depth^0.25 makes far (small) depths visible.
    for (uint32_t y = 0; y < f.height; ++y)
      for (uint32_t x = 0; x < f.width; ++x) {
        uint32_t px = std::min(level.width - 1, x >> pyramidLevel);
        uint32_t py = std::min(level.height - 1, y >> pyramidLevel);
        float d = std::pow(std::max(level.depth[size_t(py) * level.width + px], 0.0f), 0.25f);
        put(img, size_t(y) * f.width + x, glm::vec3(d));
      }
    return img;
  }
  if (view == "culled") {
    // The shaded frame, darkened, with the screen rectangles of the objects that were inside the
    // frustum but not drawn (occluded or sub-pixel) outlined in red.
    img = f.color;
    for (size_t i = 0; i < img.size(); ++i)
      if (i % 4 != 3) img[i] *= 0.5f;
    std::vector<char> drawn(scene.objects.size(), 0);
    for (uint32_t o : f.drawnObjects) drawn[o] = 1;
    FrameMath fm = computeFrameMath(camera, f.width, f.height);
    for (size_t o = 0; o < scene.objects.size(); ++o) {
      if (drawn[o]) continue;
      glm::dvec4 s = objectBoundsWorld(scene, scene.objects[o]);
      if (!sphereInFrustum(fm, camera, glm::dvec3(s), s.w)) continue;
      glm::dvec3 v = glm::dvec3(fm.view * glm::dvec4(glm::dvec3(s) - camera.position, 0.0));
      if (-(v.z + s.w) <= camera.nearPlane) continue;
      glm::dvec2 lo(1e30), hi(-1e30);
      for (int c = 0; c < 8; ++c) {
        glm::dvec3 q = v + s.w * glm::dvec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1);
        const double w = fm.orthographic ? 1.0 : -q.z;
        glm::dvec2 ndc(fm.proj[0][0] * q.x / w, fm.proj[1][1] * q.y / w);
        lo = glm::min(lo, ndc);
        hi = glm::max(hi, ndc);
      }
      int x0 = std::max(0, int((lo.x * 0.5 + 0.5) * f.width)), x1 = std::min(int(f.width) - 1, int((hi.x * 0.5 + 0.5) * f.width));
      int y0 = std::max(0, int((lo.y * 0.5 + 0.5) * f.height)), y1 = std::min(int(f.height) - 1, int((hi.y * 0.5 + 0.5) * f.height));
      const glm::vec3 red(1.0f, 0.1f, 0.1f);
      for (int x = x0; x <= x1; ++x) {
        put(img, size_t(y0) * f.width + x, red);
        put(img, size_t(y1) * f.width + x, red);
      }
      for (int y = y0; y <= y1; ++y) {
        put(img, size_t(y) * f.width + x0, red);
        put(img, size_t(y) * f.width + x1, red);
      }
    }
    return img;
  }
  return makeError(ErrorCode::InvalidArgument, fmt::format("unknown --view '{}'", view));
}

}  // namespace visbuf::tools
