// visbuf view: a window onto a scene, built only on the public API as a host engine would use it: the viewer's
// own Vulkan instance, device and swapchain (view_host.h), the device handed to visbuf with gpu::Device::adopt,
// and each frame recorded by Renderer::record and blitted to the swapchain image in the same submit.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include <fmt/format.h>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "cli_checks.h"
#include "commands.h"
#include "debug_views.h"
#include "stats_output.h"
#include "view_host.h"
#include "visbuf/core/image_io.h"
#include "visbuf/gpu/device.h"
#include "visbuf/render/renderer.h"

namespace visbuf::tools {

namespace {

constexpr const char* kKeys =
    "Keys (window focused):\n"
    "  W A S D      fly forward / left / back / right      Q / E   down / up      Shift   5x faster\n"
    "  right mouse  hold and drag to look around\n"
    "  L / K        LOD threshold x2 / /2 (pixels of projected error)\n"
    "  C            culling: none -> frustum -> occlusion\n"
    "  M            micro-raster (software raster of small objects) on / off\n"
    "  F            freeze culling (keep the draw lists of the frame it was pressed on; visbuf and gbuffer paths)\n"
    "  V            debug view: shaded -> objects -> triangles -> lod -> culled -> pyramid -> overdraw (render --view;\n"
    "               built from read-back IDs, draw lists and pyramid levels: each such frame is a renderFrame)\n"
    "  R            back to the start camera          P   print the newest finished frame's stats\n"
    "  G            next camera of the file (glTF cameras, then the framing default camera)\n"
    "  Esc          quit\n";

int fail(const Error& e) {
  std::fprintf(stderr, "visbuf view: error (%s): %s\n", errorCodeName(e.code),
               printable(e.message, e.code == ErrorCode::NoDevice).c_str());
  return 1;
}

// Options that contradict each other: a usage error (exit 2).
int usage(const std::string& message) {
  std::fprintf(stderr, "visbuf view: %s (see visbuf view --help)\n", printable(message).c_str());
  return 2;
}

int badValue(const std::string& message) {
  std::fprintf(stderr, "visbuf view: %s (see visbuf view --help)\n", printable(message).c_str());
  return 1;
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& ch : ext) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return ext;
}

// Rodrigues: v turned by `angle` radians about the unit axis k.
glm::dvec3 rotate(const glm::dvec3& v, const glm::dvec3& k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(k, v) * s + k * glm::dot(k, v) * (1.0 - c);
}

// A fly camera: position and view direction; the scene camera's up stays the world's up.
struct FlyCamera {
  Camera base;
  glm::dvec3 position{0.0};
  glm::dvec3 forward{0.0, 0.0, -1.0};
  glm::dvec3 up{0.0, 1.0, 0.0};
  double focus = 1.0;  // distance to the target kept in Camera::target
  double speed = 1.0;  // units per second

  explicit FlyCamera(const Camera& c) : base(c) { reset(); }
  void reset() {
    position = base.position;
    const glm::dvec3 d = base.target - base.position;
    focus = std::max(glm::length(d), 1e-3);
    forward = d / focus;
    up = glm::length(base.up) > 0.0 ? glm::normalize(base.up) : glm::dvec3(0.0, 1.0, 0.0);
    speed = std::max(focus, 1.0) * 0.5;
  }
  void move(const glm::dvec3& local, double seconds, bool fast) {  // local: right, up, forward
    const glm::dvec3 right = glm::normalize(glm::cross(forward, up));
    position += (right * local.x + up * local.y + forward * local.z) * (speed * seconds * (fast ? 5.0 : 1.0));
  }
  void look(double dx, double dy) {  // cursor pixels
    const double sensitivity = 0.003;
    forward = glm::normalize(rotate(forward, up, -dx * sensitivity));
    const glm::dvec3 right = glm::normalize(glm::cross(forward, up));
    const glm::dvec3 pitched = glm::normalize(rotate(forward, right, -dy * sensitivity));
    if (std::abs(glm::dot(pitched, up)) < 0.995) forward = pitched;  // never straight up or down
  }
  Camera camera() const {
    Camera c = base;
    c.position = position;
    c.target = position + forward * focus;
    c.up = up;
    return c;
  }
};

std::string count(uint64_t n) {
  if (n >= 10'000'000) return fmt::format("{:.1f}M", double(n) / 1e6);
  if (n >= 10'000) return fmt::format("{:.1f}K", double(n) / 1e3);
  return fmt::format("{}", n);
}

const char* swRasterText(SwRasterMode m) {
  return m == SwRasterMode::On ? "on" : m == SwRasterMode::Off ? "off" : "auto";
}

// Key edges: true once per press (sticky keys keep a press seen between two polls).
struct KeyEdges {
  bool down[GLFW_KEY_LAST + 1] = {};
  bool pressed(GLFWwindow* w, int key) {
    const bool now = glfwGetKey(w, key) == GLFW_PRESS;
    const bool edge = now && !down[key];
    down[key] = now;
    return edge;
  }
};

}  // namespace

void addViewCommand(CLI::App& app, ViewCommand& c) {
  CLI::App* sub = app.add_subcommand(
      "view", "open a window onto a scene: fly camera, live GPU times and culling stats in the title");
  addSceneOptions(*sub, c.scene);
  addCameraOptions(*sub, c.camera);
  sub->add_option("--size", c.size, "window size WxH")->check(imageSize())->capture_default_str();
  sub->add_option("--path", c.path, "visbuf | forward | gbuffer (as render --path)")
      ->check(CLI::IsMember({"visbuf", "forward", "gbuffer"}))
      ->capture_default_str();
  sub->add_option("--device", c.device,
                  "auto | cpu | gpu | N among the devices that can present to the window (auto prefers a GPU)")
      ->capture_default_str();
  sub->add_option("--cull", c.cull, "starting culling: none | frustum | occlusion (key C cycles)")
      ->check(CLI::IsMember({"none", "frustum", "occlusion"}))
      ->capture_default_str();
  sub->add_option("--lod-error", c.lodError, "starting LOD threshold in pixels (keys L / K)")
      ->check(finiteNumber(0.0, 1e6))
      ->capture_default_str();
  sub->add_flag("--no-lod", c.noLod, "start with LOD off (full-detail meshes; L turns it on at 1 px)");
  sub->add_option("--sw-raster", c.swRaster, "starting micro-raster: auto | on | off (key M toggles on / off)")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  sub->add_option("--shading", c.shading, "visbuf shading: auto | uber | covered | classified (as render --shading)")
      ->check(CLI::IsMember({"auto", "uber", "covered", "classified"}))
      ->capture_default_str();
  sub->add_option("--draw-capacity", c.drawCapacity, "max draw commands per phase and draw list (default: one per object)")
      ->check(unsignedIn(1, UINT32_MAX));
  sub->add_flag("--wide-ids", c.wideIds, "force the 64-bit visibility target");
  sub->add_flag("--validation", c.validation,
                "Vulkan validation layer with a message counter: any warning or error makes the exit status 3");
  sub->add_option("--frames-in-flight", c.framesInFlight, "frames queued at once (2 or 3)")
      ->check(unsignedIn(2, 3))
      ->capture_default_str();
  sub->add_option("--present", c.present, "fifo (vsync) | mailbox (where offered, else fifo)")
      ->check(CLI::IsMember({"fifo", "mailbox"}))
      ->capture_default_str();
  sub->add_option("--surface", c.surface,
                  "srgb: an sRGB swapchain where offered (the blit encodes) | unorm: a UNORM swapchain, encoded by "
                  "a blit to an sRGB twin image whose bytes are copied")
      ->check(CLI::IsMember({"srgb", "unorm"}))
      ->capture_default_str();
  sub->add_option("--frames", c.frames, "exit after N presented frames (0: when the window closes; --screenshot: 1)")
      ->check(unsignedIn(0, 100'000'000));
  sub->add_option("--screenshot", c.screenshot,
                  "after the last of --frames N frames (camera fixed: the scene's or --camera-pos/--camera-target), "
                  "write that frame's colour output as render -o does (.png, .jpg, .exr, .tif), then exit");
  sub->add_option("--time", c.time, "animation time in seconds (skinned scenes)")
      ->check(finiteNumber(-1e9, 1e9))
      ->capture_default_str();
  sub->add_flag("--animate", c.animate,
                "play the animation from --time (real time; with --screenshot 1/30 s per frame)");
  std::vector<std::string> views{"shaded"};
  for (const std::string& v : debugViewNames()) views.push_back(v);
  sub->add_option("--view", c.view, "start in this view: shaded | objects | triangles | lod | culled | pyramid | overdraw")
      ->check(CLI::IsMember(views))
      ->capture_default_str();
  sub->footer(std::string(kKeys) +
              "Without a display (no DISPLAY / WAYLAND_DISPLAY, or the window system cannot be opened) view exits 1: "
              "use visbuf render for headless images.\n"
              "Exit codes: 0 ok; 1 bad input, no display or no device; 2 usage; 3 validation messages.\n");
}

int runView(const ViewCommand& c) {
  auto size = parseSize(c.size);
  if (!size) return badValue(size.error().message);
  auto devOptions = gpu::parseDeviceOption(c.device, {.validation = false, .verbose = false});
  if (!devOptions) return fail(devOptions.error());
  if (!(c.lodError >= 0.0f)) return badValue("--lod-error must be >= 0");
  std::vector<OutputFile> outputs;
  if (!c.screenshot.empty()) outputs.push_back({"--screenshot", c.screenshot});
  noteSceneInputs(c.scene);
  if (Status s = checkOutputs(outputs); !s) return fail(s.error());
  if (!c.screenshot.empty()) {
    const std::string ext = lowerExtension(c.screenshot);
    if (ext != ".png" && ext != ".jpg" && ext != ".jpeg" && ext != ".exr" && ext != ".tif" && ext != ".tiff")
      return fail({ErrorCode::InvalidArgument,
                   fmt::format("--screenshot '{}': the image must be .png, .jpg, .exr or .tif", c.screenshot)});
  }
  const bool screenshot = !c.screenshot.empty();
  const uint32_t frames = screenshot ? std::max(c.frames, 1u) : c.frames;

  if (std::string why = openWindowSystem(); !why.empty()) {
    std::fprintf(stderr, "visbuf view: no display (%s); use `visbuf render` for headless images\n",
                 printable(why).c_str());
    return 1;
  }
  struct WindowSystem {
    ~WindowSystem() { closeWindowSystem(); }
  } windowSystem;

  auto scene = loadScene(c.scene);
  if (!scene) return fail(scene.error());
  if (Status s = checkOutputs(outputs); !s) return fail(s.error());
  if (camerasListRequested(c.camera)) {
    std::fputs(describeCameras(*scene).c_str(), stdout);
    return 0;
  }
  // A file with cameras starts from its first one unless the command line placed the camera.
  CameraOptions cameraOptions = c.camera;
  if (cameraOptions.camera.empty() && cameraOptions.position.empty() && cameraOptions.target.empty() &&
      !scene->cameras.empty())
    cameraOptions.camera = "gltf";
  auto startCamera = makeCamera(cameraOptions, *scene);
  if (!startCamera) return fail(startCamera.error());

  ViewHostOptions ho;
  ho.width = size->first;
  ho.height = size->second;
  ho.resizable = !screenshot;
  ho.validation = c.validation;
  ho.device = *devOptions;
  ho.mailbox = c.present == "mailbox";
  ho.unormSurface = c.surface == "unorm";
  ho.framesInFlight = c.framesInFlight;
  auto host = ViewHost::create(ho);
  if (!host) return fail(host.error());
  GLFWwindow* window = (*host)->window();

  auto device = gpu::Device::adopt((*host)->external());
  if (!device) return fail(device.error());
  RendererConfig rc;
  rc.width = std::max((*host)->extent().width, 1u);
  rc.height = std::max((*host)->extent().height, 1u);
  rc.drawCapacity = c.drawCapacity;
  rc.forceWideIds = c.wideIds;
  rc.framesInFlight = c.framesInFlight;
  auto renderer = Renderer::create(**device, *scene, rc);
  if (!renderer) return fail(renderer.error());
  uint32_t renderWidth = rc.width, renderHeight = rc.height;

  FrameOptions fo;
  fo.path = c.path == "forward" ? RenderPath::Forward : c.path == "gbuffer" ? RenderPath::GBuffer : RenderPath::Visbuf;
  fo.cull = c.cull == "none" ? CullMode::None : c.cull == "frustum" ? CullMode::Frustum : CullMode::Occlusion;
  fo.lodErrorPixels = c.noLod ? 0.0f : c.lodError;
  fo.swRaster = parseSwRasterMode(c.swRaster);
  fo.shading = parseShadingMode(c.shading);
  fo.readColor = false;  // record(): the host reads the outputs itself

  std::printf("visbuf view: %s, %zu objects; %ux%u on %s; %s; %u frames in flight\n", printable(c.scene.scene).c_str(),
              scene->objects.size(), (*host)->extent().width, (*host)->extent().height,
              printable((*host)->deviceName()).c_str(), (*host)->presentDescription().c_str(), c.framesInFlight);
  if (!screenshot) std::printf("%s", kKeys);
  std::fflush(stdout);

  std::string view = c.view;
  // Debug views other than overdraw read back the visbuf path's IDs, draw lists or pyramid (as render --view).
  auto viewSupported = [&](const std::string& v) {
    return v == "shaded" || v == "overdraw" || fo.path == RenderPath::Visbuf;
  };
  if (!viewSupported(view)) return usage(fmt::format("--view {} needs --path visbuf", view));
  FlyCamera fly(*startCamera);
  // G cycles from here (makeCamera accepted the value: gltf or gltf:N).
  size_t cameraIndex = cameraOptions.camera.empty()      ? scene->cameras.size()
                       : cameraOptions.camera.size() > 5 ? size_t(std::stoull(cameraOptions.camera.substr(5)))
                                                    : 0;
  KeyEdges keys;
  bool looking = false;
  double lastX = 0.0, lastY = 0.0;
  bool recreate = false;
  uint64_t recorded = 0, presented = 0;
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  auto last = start, titleAt = start;
  uint64_t titleFrames = 0;
  std::vector<float> viewShot;  // a debug view's screenshot: the CPU image itself
  uint32_t viewShotWidth = 0, viewShotHeight = 0;

  while (!glfwWindowShouldClose(window) && (frames == 0 || presented < frames)) {
    glfwPollEvents();
    const auto now = Clock::now();
    const double dt = std::min(std::chrono::duration<double>(now - last).count(), 0.25);
    last = now;

    if (recreate || (*host)->resized()) {
      if (Status s = (*host)->recreateSwapchain(); !s) return fail(s.error());
      recreate = false;
      const VkExtent2D e = (*host)->extent();
      if (e.width == 0 || e.height == 0) {  // minimised
        glfwWaitEvents();
        continue;
      }
      if (e.width != renderWidth || e.height != renderHeight) {
        if (Status s = (*renderer)->resize(e.width, e.height); !s) return fail(s.error());
        renderWidth = e.width;
        renderHeight = e.height;
      }
    }

    if (!screenshot) {
      if (glfwGetKey(window, GLFW_KEY_ESCAPE) == GLFW_PRESS) glfwSetWindowShouldClose(window, GLFW_TRUE);
      const bool fast = glfwGetKey(window, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                        glfwGetKey(window, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
      auto held = [&](int key) { return glfwGetKey(window, key) == GLFW_PRESS ? 1.0 : 0.0; };
      const glm::dvec3 local{held(GLFW_KEY_D) - held(GLFW_KEY_A), held(GLFW_KEY_E) - held(GLFW_KEY_Q),
                             held(GLFW_KEY_W) - held(GLFW_KEY_S)};
      if (local != glm::dvec3(0.0)) fly.move(local, dt, fast);
      double x = 0.0, y = 0.0;
      glfwGetCursorPos(window, &x, &y);
      const bool rightButton = glfwGetMouseButton(window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
      if (rightButton && looking) fly.look(x - lastX, y - lastY);
      looking = rightButton;
      lastX = x;
      lastY = y;
      if (keys.pressed(window, GLFW_KEY_L)) {
        fo.lodErrorPixels = fo.lodErrorPixels <= 0.0f ? 1.0f : std::min(fo.lodErrorPixels * 2.0f, 1024.0f);
        std::printf("LOD threshold %g px\n", double(fo.lodErrorPixels));
      }
      if (keys.pressed(window, GLFW_KEY_K)) {
        fo.lodErrorPixels = std::max(fo.lodErrorPixels * 0.5f, 1.0f / 64.0f);
        std::printf("LOD threshold %g px\n", double(fo.lodErrorPixels));
      }
      if (keys.pressed(window, GLFW_KEY_C)) {
        fo.cull = fo.cull == CullMode::None ? CullMode::Frustum : fo.cull == CullMode::Frustum ? CullMode::Occlusion
                                                                                               : CullMode::None;
        std::printf("culling %s\n", cullModeName(fo.cull));
      }
      if (keys.pressed(window, GLFW_KEY_M)) {
        fo.swRaster = fo.swRaster == SwRasterMode::Off ? SwRasterMode::On : SwRasterMode::Off;
        std::printf("micro-raster %s\n", swRasterText(fo.swRaster));
      }
      if (keys.pressed(window, GLFW_KEY_F)) {
        if (fo.path == RenderPath::Forward) {
          std::printf("freeze culling: the forward path culls on the CPU every frame (visbuf and gbuffer only)\n");
        } else {
          fo.freezeCulling = !fo.freezeCulling;
          std::printf("culling %s\n", fo.freezeCulling ? "FROZEN" : "live");
        }
      }
      if (keys.pressed(window, GLFW_KEY_V)) {
        std::vector<std::string> cycle{"shaded"};
        for (const std::string& v : debugViewNames())
          if (viewSupported(v)) cycle.push_back(v);
        const auto at = std::find(cycle.begin(), cycle.end(), view);
        view = at == cycle.end() || at + 1 == cycle.end() ? cycle.front() : *(at + 1);
        std::printf("view %s\n", view.c_str());
      }
      if (keys.pressed(window, GLFW_KEY_R)) fly.reset();
      if (keys.pressed(window, GLFW_KEY_G) && !scene->cameras.empty()) {  // (index cameras.size(): the default)
        cameraIndex = (cameraIndex + 1) % (scene->cameras.size() + 1);
        const bool file = cameraIndex < scene->cameras.size();
        fly = FlyCamera(file ? scene->cameras[cameraIndex].camera : scene->defaultCamera);
        std::printf("camera %s\n", file ? fmt::format("{} '{}'", cameraIndex,
                                                      printable(scene->cameras[cameraIndex].name)).c_str()
                                        : "default");
      }
      if (keys.pressed(window, GLFW_KEY_P)) {
        if (const auto& st = (*renderer)->completedStats()) std::printf("%s", formatStats(*st).c_str());
      }
      std::fflush(stdout);
    }
    if (c.animate)
      fo.animationTime = c.time + (screenshot ? double(recorded) / 30.0 : std::chrono::duration<double>(now - start).count());
    else
      fo.animationTime = c.time;

    // Frame `recorded` uses slot recorded % N: beginFrame waits for the frame N earlier (record()'s contract).
    const uint32_t slot = uint32_t(recorded % c.framesInFlight);
    auto acquired = (*host)->beginFrame(slot);
    if (!acquired) return fail(acquired.error());
    if (!*acquired) {
      recreate = true;
      continue;
    }
    const bool readback = screenshot && presented + 1 == frames;
    Result<ViewHost::Presented> result = ViewHost::Presented{};
    if (view == "shaded") {
      auto frame = (*renderer)->record({fly.camera(), fo, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL});
      if (!frame) return fail(frame.error());
      result = (*host)->submitAndPresent(slot, *frame, readback);
    } else {
      // A debug view: the frame is rendered and read back (renderFrame waits for it), the view is built on the CPU
      // as render --view builds it, and the image is presented like a frame.
      FrameOptions vo = fo;
      prepareViewOptions(view, vo);
      auto frame = (*renderer)->renderFrame(fly.camera(), vo);
      if (!frame) return fail(frame.error());
      auto image = buildDebugView(view, *frame, *scene, fly.camera(), 0);
      if (!image) return fail(image.error());
      result = (*host)->presentPixels(slot, *image, frame->width, frame->height);
      if (readback) {
        viewShot = std::move(image.value());
        viewShotWidth = frame->width;
        viewShotHeight = frame->height;
      }
    }
    if (!result) return fail(result.error());
    ++recorded;
    if (result->presented) {
      ++presented;
      ++titleFrames;
    }
    recreate = result->recreate;
    if (readback && !result->presented) return fail({ErrorCode::InvalidArgument, "the screenshot frame was not presented"});

    const double sinceTitle = std::chrono::duration<double>(now - titleAt).count();
    if (sinceTitle >= 0.25) {
      std::string title = fmt::format("visbuf view | {:.1f} fps", double(titleFrames) / sinceTitle);
      if (const auto& st = (*renderer)->completedStats())
        title += fmt::format(" | GPU {:.2f} ms | {} draws | {} tris", st->gpuMs, count(st->cull.drawsRendered),
                             count(st->trianglesDrawn));
      if (view != "shaded") title += " | view " + view;
      title += fmt::format(" | {} | cull {}{} | LOD {} | micro-raster {}", renderPathName(fo.path),
                           cullModeName(fo.cull), fo.freezeCulling ? " (frozen)" : "",
                           fo.lodErrorPixels > 0.0f ? fmt::format("{:g} px", double(fo.lodErrorPixels))
                                                    : std::string("off"),
                           swRasterText(fo.swRaster));
      glfwSetWindowTitle(window, title.c_str());
      titleAt = now;
      titleFrames = 0;
    }
  }
  (*host)->waitIdle();

  if (screenshot) {
    uint32_t w = viewShotWidth, h = viewShotHeight;
    Result<std::vector<float>> color = std::move(viewShot);
    if (view == "shaded") color = (*host)->readColor(w, h);
    if (!color) return fail(color.error());
    if (Status s = writeColorImage(c.screenshot, w, h, *color); !s) return fail(s.error());
    std::printf("screenshot    %s (%ux%u, frame %llu)\n", printable(c.screenshot).c_str(), w, h,
                (unsigned long long)presented);
  }
  if (const auto& st = (*renderer)->completedStats()) std::printf("%s", formatStats(*st).c_str());
  std::printf("presented %llu frames\n", (unsigned long long)presented);
  renderer->reset();
  device->reset();  // visbuf lets go of its objects before the host destroys the device
  const uint32_t messages = (*host)->validationMessages();
  if (c.validation) std::printf("validation messages: %u\n", messages);
  if (messages > 0) {
    std::fprintf(stderr, "visbuf view: %u validation message(s)\n", messages);
    return 3;
  }
  return 0;
}

}  // namespace visbuf::tools
