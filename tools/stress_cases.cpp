// The stress cases of precision (far from the origin, hard triangles, depth gaps) and the list of every case;
// the input and limit cases are in stress_limits.cpp. Every bound below is stated in StressCase::bound and checked
// here; the measured values go to the rows whether they pass or not. Rendering uses LOD off wherever pixels are
// compared with a reference (the reference knows LOD 0 only).
#include "stress_cases.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "visbuf/scene/generate.h"
#include "stress_reference.h"
#include "stress_scene.h"

namespace visbuf::tools {

bool StressCase::passed() const {
  for (const StressRow& r : rows)
    if (r.values.contains("pass") && r.values["pass"].is_boolean() && !r.values["pass"].get<bool>()) return false;
  return !rows.empty();
}

namespace stress {

// ---- far from the origin ---------------------------------------------------------------------------

// Bounds on the well-conditioned measures of AttributeErrors (stress_reference.h says why these).
struct AttributeBounds {
  double positionPixels, offSurface, lambdaPixels, derivative;
  bool check(const AttributeErrors& e) const {
    return e.pixels > 0 && e.positionPixels <= positionPixels && e.offSurface <= offSurface &&
           e.lambdaPixels <= lambdaPixels && e.derivative <= derivative;
  }
  std::string text() const {
    return fmt::format("reconstructed point within {:.0e} px of the pixel centre and within {:.0e} x its distance "
                       "of the triangle's plane, barycentrics within {:.0e} px, derivatives within {:.0e} of the "
                       "pixel's largest (where the triangle is more than 1.15 degrees from edge-on; edge-on pixels are "
                       "counted and reported apart)",
                       positionPixels, offSurface, lambdaPixels, derivative);
  }
};

constexpr AttributeBounds kFarBounds{0.05, 1e-5, 0.05, 1e-2};

StressCase farFromOrigin(const StressContext& ctx) {
  StressCase c{"far-from-origin",
               "a field of knots and its camera translated to 10^3 .. 10^7 units from the origin; every covered "
               "pixel's reconstructed attributes vs a double-precision ray cast",
               "scene anchor at the content (as bake and the generators set it): " + kFarBounds.text() +
                   " at every distance, and no distance worse than 2x the origin's error + 1e-7. Rows with the "
                   "anchor left at the origin only inform: they show what the anchor buys",
               {}};
  const uint32_t w = ctx.reduced ? 240 : 640, h = ctx.reduced ? 160 : 400;
  FieldParams p;
  p.objects = ctx.reduced ? 200 : 2000;
  p.extent = 30.0;
  p.mesh = makeTorusKnot(ctx.reduced ? 64 : 160, ctx.reduced ? 12 : 32);
  auto base = makeFieldScene(p);
  if (!base) return c.rows.push_back(errorRow("field", base.error())), c;
  const glm::dvec3 dir = glm::normalize(glm::dvec3(1.0, -0.5, 0.25));
  AttributeErrors atOrigin;
  for (bool anchored : {true, false}) {
    for (double d : {0.0, 1e3, 1e5, 1e6, 1e7}) {
      if (!anchored && d == 0.0) continue;
      Scene s = *base;
      const glm::dvec3 offset = dir * d;
      for (Object& o : s.objects) o.transform = glm::translate(glm::dmat4(1.0), offset) * o.transform;
      s.anchor = anchored ? offset : glm::dvec3(0.0);
      const Camera cam = lookFrom(glm::dvec3(0.0, 8.0, 70.0) + offset, offset);
      const std::string label = fmt::format("{:.0e} units, anchor at {}", d, anchored ? "content" : "origin");
      auto r = renderOnce(ctx.device, s, cam, w, h, true);
      if (!r) {
        c.rows.push_back(errorRow(label, r.error()));
        continue;
      }
      const AttributeErrors e = compareAttributes(s, cam, r->frame);
      if (d == 0.0) atOrigin = e;
      StressRow row{{{"case", label}, {"distance", d}, {"anchor", anchored ? "content" : "origin"}}};
      appendValues(row, e.toJson());
      if (anchored) {
        const bool notWorse = e.positionPixels <= 2 * atOrigin.positionPixels + 1e-6 &&
                              e.offSurface <= 2 * atOrigin.offSurface + 1e-7 &&
                              e.lambdaPixels <= 2 * atOrigin.lambdaPixels + 1e-6;
        row.values["pass"] = kFarBounds.check(e) && notWorse && e.pixels > size_t(w) * h / 20;
      } else {
        row.values["pass"] = nullptr;
      }
      c.rows.push_back(std::move(row));
    }
  }
  return c;
}

// ---- hard triangles ---------------------------------------------------------------------------------

constexpr AttributeBounds kTriangleBounds{0.05, 1e-5, 0.05, 1e-2};


// Thin triangles through the screen centre at 64 angles, aspect 1:2000, each at its own depth.
MeshSource slivers() {
  std::vector<glm::vec3> c;
  for (int k = 0; k < 64; ++k) {
    const float a = float(k) * 3.14159265f / 64.0f, z = -5.0f - 0.01f * float(k);
    const glm::vec3 d(std::cos(a), std::sin(a), 0.0f), n(-d.y, d.x, 0.0f);
    c.push_back(glm::vec3(0, 0, z) - 4.0f * d);
    c.push_back(glm::vec3(0, 0, z) + 4.0f * d);
    c.push_back(glm::vec3(0, 0, z) + 4.0f * d + 0.004f * n);
  }
  return triangleSoup("slivers", c);
}

// A jittered grid of triangles about 0.4 px across (most cover no pixel centre; the rest cover one).
MeshSource subPixel(uint32_t w, uint32_t h) {
  std::vector<glm::vec3> c;
  const float pixel = 2.0f * 5.0f * std::tan(glm::radians(30.0f)) / float(h);  // world size of a pixel at z = -5
  Rng rng(7);
  for (uint32_t y = 0; y < h / 2; ++y)
    for (uint32_t x = 0; x < w / 2; ++x) {
      const glm::vec3 o((float(x) * 2.0f - float(w) / 2.0f + float(rng.uniform())) * pixel,
                        (float(y) * 2.0f - float(h) / 2.0f + float(rng.uniform())) * pixel, -5.0f);
      c.push_back(o);
      c.push_back(o + glm::vec3(0.4f * pixel, 0.0f, -0.001f));
      c.push_back(o + glm::vec3(0.1f * pixel, 0.4f * pixel, 0.001f));
    }
  return triangleSoup("sub-pixel", c);
}

// One triangle about 10^4 pixels across, tilted so its depth varies over the screen.
MeshSource huge() {
  return triangleSoup("10^4 px", {{-150.0f, -120.0f, -3.0f}, {150.0f, -120.0f, -3.0f}, {0.0f, 150.0f, -12.0f}});
}

// Triangles with a vertex behind the camera (clipped by the rasteriser; w < 0 in the reconstruction).
MeshSource nearCrossing() {
  return triangleSoup("near-plane", {{-3.0f, -1.0f, -4.0f}, {0.0f, -1.0f, 3.0f}, {3.0f, -1.0f, -4.0f},
                                     {1.0f, -2.0f, -2.0f}, {1.0f, 0.0f, 5.0f}, {1.0f, 2.0f, -2.0f}});
}

StressCase hardTriangles(const StressContext& ctx) {
  StressCase c{"triangles",
               "slivers (1:2000), sub-pixel triangles, a 10^4-pixel triangle, triangles crossing the near plane "
               "and a ground plane at a grazing angle: reconstruction vs the double-precision ray cast",
               kTriangleBounds.text() + ", on every covered pixel",
               {}};
  const uint32_t w = ctx.reduced ? 240 : 640, h = ctx.reduced ? 160 : 400;
  struct Sub {
    std::string name;
    MeshSource mesh;
    glm::dmat4 transform;
    Camera camera;
  };
  std::vector<Sub> subs;
  subs.push_back({"slivers", slivers(), glm::dmat4(1.0), kAtOrigin});
  subs.push_back({"sub-pixel", subPixel(w, h), glm::dmat4(1.0), kAtOrigin});
  subs.push_back({"10^4 px wide", huge(), glm::dmat4(1.0), kAtOrigin});
  subs.push_back({"crossing the near plane", nearCrossing(), glm::dmat4(1.0), kAtOrigin});
  // A 2000-unit ground seen from 0.05 units above it, looking at the horizon: 89.9+ degree incidence far off.
  subs.push_back({"grazing ground", makeGround(64), glm::scale(glm::dmat4(1.0), glm::dvec3(2000.0, 1.0, 2000.0)),
                  lookFrom(glm::dvec3(0.0, 0.05, 0.0), glm::dvec3(0.0, 0.02, -1.0), 0.01)});
  for (Sub& sub : subs) {
    auto scene = sceneOf(sub.name, {sub.mesh}, {{0u, sub.transform}}, sub.camera);
    if (!scene) {
      c.rows.push_back(errorRow(sub.name, scene.error()));
      continue;
    }
    auto r = renderOnce(ctx.device, *scene, sub.camera, w, h, true);
    if (!r) {
      c.rows.push_back(errorRow(sub.name, r.error()));
      continue;
    }
    const AttributeErrors e = compareAttributes(*scene, sub.camera, r->frame);
    StressRow row{{{"case", sub.name}, {"triangles", scene->meshes[0].triangleCount()}}};
    appendValues(row, e.toJson());
    row.values["pass"] = kTriangleBounds.check(e);
    c.rows.push_back(std::move(row));
  }
  return c;
}

// ---- depth precision --------------------------------------------------------------------------------

// Quad in the XY plane, facing +Z, side 1, centred on the origin.
MeshSource quad() {
  return triangleSoup("quad", {{-0.5f, -0.5f, 0.0f}, {0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.0f},
                               {-0.5f, -0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {-0.5f, 0.5f, 0.0f}});
}

constexpr double kMaxResolvedGap = 1e-5;  // relative to the distance

StressCase depthGap(const StressContext& ctx) {
  StressCase c{"depth-gap",
               "pairs of parallel quads, the front one at distance d and a larger one behind it at d(1+g), for "
               "relative gaps g = 1e-1 .. 1e-8 side by side; the front quad must own every pixel it covers in "
               "every one of several sub-pixel-jittered views (no ID flicker)",
               fmt::format("the smallest relative gap resolved at every distance is <= {:.0e} (reverse-Z float "
                           "depth: precision relative to the distance, so the same at every distance)",
                           kMaxResolvedGap),
               {}};
  const std::vector<double> gaps = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
  const std::vector<double> distances =
      ctx.reduced ? std::vector<double>{1.0, 100.0, 1e4} : std::vector<double>{1.0, 10.0, 100.0, 1e3, 1e4, 1e5};
  const int views = ctx.reduced ? 2 : 6;
  const uint32_t w = 64 * uint32_t(gaps.size()), h = 64;
  for (double d : distances) {
    // Slot k: front quad A_k (object 2k) of side 0.8 s at x_k, back quad B_k (object 2k+1) of side s.
    const double s = 2.0 * d * std::tan(glm::radians(30.0)) * 0.9;  // slot size: 90 % of the view height
    // Two orders of the same objects: front quads first (objects 2k = A_k, 2k+1 = B_k) and back quads first
    // (2k = B_k, 2k+1 = A_k). With equal depths the draw order would decide; only a gap that both orders
    // resolve counts.
    std::vector<std::pair<uint32_t, glm::dmat4>> frontFirst, backFirst, fronts;
    for (size_t k = 0; k < gaps.size(); ++k) {
      const double x = (double(k) - 0.5 * double(gaps.size() - 1)) * s / 0.9;
      auto at = [&](double z, double side) {
        return glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(x, 0.0, -z)), glm::dvec3(side, side, 1.0));
      };
      const glm::dmat4 a = at(d, 0.8 * s), b = at(d * (1.0 + gaps[k]), s);
      frontFirst.insert(frontFirst.end(), {{0u, a}, {0u, b}});
      backFirst.insert(backFirst.end(), {{0u, b}, {0u, a}});
      fronts.push_back({0u, a});
    }
    const Camera cam = lookFrom(glm::dvec3(0.0), glm::dvec3(0.0, 0.0, -1.0), 0.1);
    auto ab = sceneOf("gaps", {quad()}, frontFirst, cam);
    auto ba = sceneOf("gaps", {quad()}, backFirst, cam);
    auto front = sceneOf("fronts", {quad()}, fronts, cam);
    if (!ab || !ba || !front) {
      c.rows.push_back(errorRow(fmt::format("d = {:g}", d), !ab ? ab.error() : !ba ? ba.error() : front.error()));
      continue;
    }
    std::vector<bool> resolved(gaps.size(), true);
    bool failed = false;
    for (int v = 0; v < views && !failed; ++v) {
      // Sub-pixel jitter of the camera position and a tiny yaw: the pixel grid samples new depths each view.
      const double pixel = s / 0.9 / 64.0;
      Camera jittered = cam;
      jittered.position = glm::dvec3(pixel * 0.37 * v, pixel * 0.23 * v, 0.0);
      jittered.target = jittered.position + glm::dvec3(1e-4 * v, 0.0, -1.0);
      auto rf = renderOnce(ctx.device, *front, jittered, w, h, false);
      for (int order = 0; order < 2 && !failed; ++order) {
        auto rb = renderOnce(ctx.device, order == 0 ? *ab : *ba, jittered, w, h, false);
        if (!rb || !rf) {
          c.rows.push_back(errorRow(fmt::format("d = {:g}", d), rb ? rf.error() : rb.error()));
          failed = true;
          break;
        }
        for (size_t i = 0; i < size_t(w) * h; ++i) {
          const uint32_t f = rf->frame.ids[2 * i];
          if (f == 0) continue;
          const uint32_t k = f - 1;  // front quad k owns this pixel: object 2k (front first) or 2k + 1
          if (rb->frame.ids[2 * i] != 2 * k + 1 + uint32_t(order)) resolved[k] = false;
        }
      }
    }
    if (failed) continue;
    // The smallest gap such that it and every larger gap resolved.
    double smallest = INFINITY;
    for (size_t k = 0; k < gaps.size() && resolved[k]; ++k) smallest = gaps[k];
    c.rows.push_back({{{"case", fmt::format("d = {:g}", d)},
                       {"distance", d},
                       {"views", views},
                       {"draw_orders", 2},
                       {"smallest_resolved_relative_gap", smallest},
                       {"smallest_resolved_gap_units", smallest * d},
                       {"pass", smallest <= kMaxResolvedGap}}});
  }
  return c;
}

}  // namespace stress

const std::vector<StressCaseInfo>& stressCases() {
  static const std::vector<StressCaseInfo> cases = {
      {"far-from-origin", stress::farFromOrigin}, {"triangles", stress::hardTriangles},
      {"depth-gap", stress::depthGap},           {"bad-input", stress::badInput},
      {"capacity", stress::capacity},            {"scale", stress::scale}};
  return cases;
}

}  // namespace visbuf::tools
