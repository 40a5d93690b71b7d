// What the bench commands share (bench_command.cpp, bench_in_flight.cpp, bench_bake_command.cpp): the failure
// line, the camera path, the median and the UTC time stamp.
#include "bench_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>

#include "cli_checks.h"

namespace visbuf::tools {

int benchFail(const Error& e) {
  std::fprintf(stderr, "visbuf bench: error (%s): %s\n", errorCodeName(e.code),
               printable(e.message, e.code == ErrorCode::NoDevice).c_str());
  return 1;
}

// ---- camera path ---------------------------------------------------------------------------------------

// Cameras for frames -warmup .. frames-1 (index 0 of the result is the first warm-up frame). The path is a
// function of t = frame / frames only, so it is reproducible and the warm-up frames lead into it.
// city: a walk down the default camera's avenue, looking left and right. Anything else: a 90-degree arc
// around the centre of the scene's bounds, starting at the default camera and spiralling in to 55% of its
// horizontal distance, rising by up to 20% of it mid-path, always looking at the centre.
std::vector<Camera> benchCameraPath(const Scene& scene, uint32_t warmup, uint32_t frames) {
  glm::dvec3 lo(INFINITY), hi(-INFINITY);
  for (const Object& o : scene.objects) {
    glm::dvec4 s = objectBoundsWorld(scene, o);
    lo = glm::min(lo, glm::dvec3(s) - s.w);
    hi = glm::max(hi, glm::dvec3(s) + s.w);
  }
  if (scene.objects.empty()) lo = hi = glm::dvec3(0.0);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  const double boundsRadius = std::max(0.5 * glm::length(hi - lo), 1e-3);
  const Camera& base = scene.defaultCamera;
  std::vector<Camera> path;
  for (int i = -int(warmup); i < int(frames); ++i) {
    const double t = double(i) / double(frames);
    Camera c = base;
    if (scene.name == "city") {
      glm::dvec3 dir = base.target - base.position;
      dir.y = 0.0;
      dir = glm::length(dir) > 0 ? glm::normalize(dir) : glm::dvec3(0, 0, -1);
      const double walk = std::min(150.0, 0.3 * boundsRadius);
      c.position = base.position + dir * (walk * t) + glm::dvec3(0.0, 0.5 * std::sin(6.283185307 * t), 0.0);
      const double yaw = 0.6 * std::sin(6.283185307 * t);
      const glm::dvec3 look(dir.x * std::cos(yaw) - dir.z * std::sin(yaw), 0.05,
                            dir.x * std::sin(yaw) + dir.z * std::cos(yaw));
      c.target = c.position + look;
    } else {
      glm::dvec3 rel = base.position - centre;
      double r0 = glm::length(glm::dvec2(rel.x, rel.z));
      if (r0 < 1e-6 * boundsRadius) r0 = 2.0 * boundsRadius, rel = glm::dvec3(0, 0, r0);
      const double az0 = std::atan2(rel.x, rel.z);
      const double az = az0 + 1.5707963268 * t;
      const double r = r0 * (1.0 - 0.45 * t);
      const double y = rel.y + 0.2 * r0 * std::sin(3.14159265359 * t);
      c.position = centre + glm::dvec3(r * std::sin(az), y, r * std::cos(az));
      c.target = centre;
    }
    path.push_back(c);
  }
  return path;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string utcNow() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace visbuf::tools
