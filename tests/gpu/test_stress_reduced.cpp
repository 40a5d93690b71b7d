// Reduced numerical-stability stress cases that fit the CI budget (the full suite is issue 7's
// `visbuf stress`): far from the origin, the frame must be the frame at the origin.
#include <glm/gtc/matrix_transform.hpp>

#include "gpu_test_util.h"
#include "visbuf/scene/generate.h"

using namespace visbuf;

namespace {

// The same field, translated by `offset` in double on the CPU, with the anchor (the origin of the GPU's
// float positions) moved with it, and the camera moved by the same offset.
Scene translatedField(double offset) {
  FieldParams p;
  p.objects = 300;
  p.extent = 30.0;
  p.mesh = makeTorusKnot(48, 12);
  Scene s = makeFieldScene(p).value();
  const glm::dvec3 d(offset, -0.5 * offset, 0.25 * offset);
  for (Object& o : s.objects) o.transform = glm::translate(glm::dmat4(1.0), d) * o.transform;
  s.anchor += d;
  s.defaultCamera.position = glm::dvec3(0.0, 8.0, 70.0) + d;
  s.defaultCamera.target = d;
  return s;
}

}  // namespace

// Camera-relative rendering: at 10^3 .. 10^7 units from the origin the decoded IDs are identical to
// the frame rendered at the origin, and the colour is identical too (same float inputs to the GPU:
// the offset cancels in double on the CPU before anything reaches a float).
GPU_TEST(Stress, FarFromOriginMatchesOrigin) {
  FrameOptions fo;
  fo.readIds = true;
  fo.lodErrorPixels = 0.0f;
  Scene origin = translatedField(0.0);
  auto r0 = Renderer::create(dev, origin, {.width = 200, .height = 120});
  ASSERT_TRUE(r0.ok());
  auto ref = (*r0)->renderFrame(origin.defaultCamera, fo);
  ASSERT_TRUE(ref.ok());
  size_t covered = 0;
  for (size_t i = 0; i < ref->ids.size(); i += 2) covered += ref->ids[i] != 0;
  ASSERT_GT(covered, 1000u);
  for (double offset : {1e3, 1e5, 1e6, 1e7}) {
    Scene far = translatedField(offset);
    auto r = Renderer::create(dev, far, {.width = 200, .height = 120});
    ASSERT_TRUE(r.ok());
    auto f = (*r)->renderFrame(far.defaultCamera, fo);
    ASSERT_TRUE(f.ok());
    size_t idMismatch = 0;
    for (size_t i = 0; i < f->ids.size(); ++i) idMismatch += f->ids[i] != ref->ids[i];
    test::ImageError e = test::compareColor(f->color, ref->color);
    std::printf("offset %.0e: %zu ID mismatches, colour max %.6f (PSNR %.1f dB)\n", offset, idMismatch, e.maxAbs, e.psnr);
    EXPECT_EQ(idMismatch, 0u) << "offset " << offset;
    EXPECT_LE(e.maxAbs, 1e-3) << "offset " << offset;
  }
}

// Bad input is rejected with a clear error before anything reaches the GPU.
GPU_TEST(Stress, NonFiniteAndDegenerateInputsAreRejected) {
  Scene s = translatedField(0.0);
  s.objects[7].transform[3][1] = NAN;
  auto r = Renderer::create(dev, s, {.width = 16, .height = 16});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("object 7"), std::string::npos) << r.error().message;
  Scene z = translatedField(0.0);
  z.objects[3].transform = glm::scale(glm::dmat4(1.0), glm::dvec3(0.0));
  auto rz = Renderer::create(dev, z, {.width = 16, .height = 16});
  ASSERT_FALSE(rz.ok());
  EXPECT_NE(rz.error().message.find("zero-scale"), std::string::npos);
}
