// Subcommand declarations: each adds its options to the CLI and runs with the parsed values.
#pragma once

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "scene_options.h"

namespace visbuf::tools {

struct RenderCommand {
  SceneOptions scene;
  CameraOptions camera;
  std::string size = "1920x1080";
  std::string path = "visbuf";
  std::string device = "auto";
  std::string cull = "occlusion";
  float lodError = 1.0f;
  bool noLod = false;
  uint32_t drawCapacity = 0;
  bool wideIds = false;
  bool validation = false;
  uint32_t frames = 1;
  double time = 0.0;     // animation time (s)
  bool animate = false;  // advance the animation by 1/30 s per frame
  std::string skinBounds = "joints";  // culling bounds of skinned instances: joints | gpu
  uint32_t skinCheck = 0;             // skinned instances to check against the CPU reference after the frames
  std::string output = "visbuf.png";
  std::string idsOut;
  std::string json;
  bool reference = false;  // also render the forward path and report the error against it
  bool referenceFull = false;  // also render visbuf with no culling and no LOD and report the error against it
  bool referenceLights = false;  // also render the same frame with every point light at every pixel (no tiles)
  std::string judge;  // heat map of both paths' per-pixel error against the exact colour (pixel_judge.h); empty: none
  bool allLights = false;        // shade every pixel with every point light (no light cull pass)
  std::string shading = "auto";  // visbuf shading: auto | uber | classified
  std::string view = "shaded";  // debug view written to -o instead of the shaded image
  int pyramidLevel = -1;        // --view pyramid: the level to show
  bool freezeCulling = false;   // cull from the scene's default camera, then render --camera-pos with it
  uint32_t msaa = 1;            // samples per pixel: 1, 2, 4 (FrameOptions::msaa)
  std::string swRaster = "auto";  // software micro-raster of small objects: auto | on | off (FrameOptions::swRaster)
  std::optional<float> swRasterPixels;  // its object size bound in pixels (FrameOptions::swRasterPixels)
  std::optional<float> swRasterArea;    // its bound on screen box area per triangle (FrameOptions::swRasterArea)
  bool noClusters = false;  // FrameOptions::clusters off
  std::string swResolve = "auto";  // FrameOptions::swResolve
  bool noEarlyClusterOcclusion = false;  // FrameOptions::earlyClusterOcclusion off
  bool alwaysPyramid = false;            // FrameOptions::skipUselessPyramid off
  double moving = 0.0;  // fraction of the movable objects moved every frame (SceneMotion)
  double churn = 0.0;   // fraction of the objects removed, added and hidden every frame (SceneMotion)
};

// visbuf render (tools/render_command.cpp). Exit codes: 0 ok; 1 bad input (an option value out of range, not
// finite or not a number, refused by the option validators with the option's name; a scene that cannot be
// loaded; an output path whose folder is missing or not writable; a request beyond the memory of the machine or
// the device -- all but the scene checked before any work); 2 usage (an unknown option, a missing argument,
// contradicting options); 3 validation messages.
void addRenderCommand(CLI::App& app, RenderCommand& cmd);
int runRender(const RenderCommand& cmd);

// visbuf bake (tools/bake_command.cpp): glTF -> pack. Exit codes: 0 ok, 1 bad input, 2 usage.
struct BakeCommand {
  std::string input;                                   // .gltf / .glb
  std::string output;                                  // pack to write
  uint32_t lodCount = MeshBuildOptions{}.maxLods;      // LOD levels incl. the full mesh, 1..MAX_LODS
  uint32_t lodMinTriangles = MeshBuildOptions{}.minTriangles;
  bool quantize = false;                               // store quantised vertices (PackWriteOptions::quantize)
  uint32_t compressionLevel = 9;                       // zstd level of the sections, 0: raw (PackWriteOptions)
  std::string json;                                    // summary as JSON; empty: none
  uint32_t maxTextureSize = 2048;                      // power of two, 1..16384
  uint32_t normalMapSize = 0;                          // --normal-map-size (TextureBakeOptions::maxNormalMapSize)
  bool noTextures = false;                             // skip texture baking (materials keep their references)
  std::string textures = "bc";                         // --textures bc|rgba8 (TextureBakeOptions::encoding)
  std::string textureQuality = "fast";                 // --texture-quality fast|normal|high
  std::vector<std::string> allowUriRoots;              // --allow-uri-root: more folders uris may point into
  uint64_t maxImagePixels = uint64_t{64} << 20;        // --max-image-pixels (TextureBakeOptions::maxImagePixels)
  uint64_t maxInstances = kDefaultMaxInstances;        // --max-instances (GltfImportOptions::maxInstances)
  uint64_t maxImportMemory = kDefaultImportMemoryBytes;  // --max-import-memory (GltfImportOptions::maxMemoryBytes)
  std::vector<std::string> ignoreRequiredExtensions;   // --ignore-required-extension (GltfImportOptions)
  bool strictImages = false;                           // --strict-images (TextureBakeOptions::dropUndecodableImages off)
  uint32_t threads = 0;                                // --threads: mesh build threads, 0 = all cores
};

void addBakeCommand(CLI::App& app, BakeCommand& cmd);
int runBake(const BakeCommand& cmd);

// visbuf extensions (tools/extensions_command.cpp): the glTF extension table (gltf_extensions.h). Exit code 0.
struct ExtensionsCommand {
  bool markdown = false;  // --markdown: the table of docs/gltf.md
};

void addExtensionsCommand(CLI::App& app, ExtensionsCommand& cmd);
int runExtensions(const ExtensionsCommand& cmd);

// visbuf bench (tools/bench_command.cpp): run time against error over a camera path and a matrix of
// path x culling x LOD, one scene per object count. Exit codes: 0 ok, 1 bad input / failure, 2 usage,
// 3 validation messages.
struct BenchCommand {
  std::string scene = "field";
  std::string mesh;                                    // field: instanced mesh file; empty = torus knot
  uint32_t lights = 0;                                 // point lights scattered over each scene
  uint64_t seed = 1;
  std::vector<uint32_t> objects;                       // empty: 100,1000 (field, city) or the file's own
  std::string size = "640x360";
  uint32_t frames = 4;                                 // measured frames (one path camera each)
  uint32_t warmup = 1;
  std::string device = "auto";
  std::vector<std::string> paths{"visbuf", "forward"};
  std::vector<std::string> cull{"none", "frustum", "occlusion"};
  std::vector<std::string> lod{"off", "0.5", "1", "2", "4"};
  std::vector<uint32_t> msaa{1};                       // samples per pixel (FrameOptions::msaa)
  std::vector<std::string> ids{"auto"};
  std::vector<std::string> shading{"auto"};           // visbuf shading: auto, uber, classified
  std::vector<std::string> swRaster{"auto"};          // visbuf software micro-raster: auto, on, off
  uint32_t materials = 0;                              // generated layouts: N generated materials (--materials)
  std::vector<std::string> vertices{"float"};          // vertex precision: float, quantized                // visbuf ID target: auto (32 bits where they fit), wide
  std::string reference = "auto";                      // auto | forward | visbuf-full
  uint64_t referenceMaxTriangles = 50'000'000;         // auto: forward reference up to this many triangles
  bool validation = false;
  std::string output = "bench-out";
  std::string commandLine;                             // as typed, recorded in the outputs
  std::vector<uint32_t> inFlight;                      // non-empty: record() with K in flight vs renderFrame instead
  uint32_t pairs = 5;                                  // --in-flight: interleaved run pairs
};

void addBenchCommand(CLI::App& app, BenchCommand& cmd, int argc, char** argv);
int runBench(const BenchCommand& cmd);

// visbuf bench-bake (tools/bench_bake_command.cpp): bake throughput and pack load time per glTF file of a
// folder. Exit codes: 0 ok, 1 failure, 2 usage, 3 validation messages.
struct BenchBakeCommand {
  std::string assets = "assets";                   // searched recursively for .gltf / .glb (the repo's assets/)
  uint32_t repeats = 5;                            // measured runs per file
  uint32_t warmup = 1;
  uint32_t maxTextureSize = 2048;                  // as bake --max-texture-size
  bool quantize = false;                           // also a quantised pack (write, load, upload, error)
  std::string device = "auto";
  bool validation = false;
  std::string output = "bench-bake-out";
  std::string commandLine;
};

void addBenchBakeCommand(CLI::App& app, BenchBakeCommand& cmd, int argc, char** argv);
int runBenchBake(const BenchBakeCommand& cmd);

// visbuf stress (tools/stress_command.cpp): named numerical-stability and scale cases with explicit bounds.
// Exit codes: 0 every bound holds, 1 a bound failed / bad input, 2 usage, 3 validation messages.
struct StressCommand {
  std::vector<std::string> cases;  // empty: all
  bool reduced = false;
  std::string device = "auto";
  bool validation = false;
  std::string assets = "assets";  // the repo's assets/ (AssimpBadData: malformed inputs)
  std::string output = "stress-out";
  std::string commandLine;
};

void addStressCommand(CLI::App& app, StressCommand& cmd, int argc, char** argv);
int runStress(const StressCommand& cmd);

// visbuf view (tools/view_command.cpp; built when GLFW is found): a window onto a scene with a fly camera, its
// own Vulkan instance / device / swapchain handed to visbuf (gpu::Device::adopt, Renderer::record). Exit codes:
// 0 ok; 1 bad input, no display or no device; 2 usage; 3 validation messages.
struct ViewCommand {
  SceneOptions scene;
  CameraOptions camera;
  std::string size = "1280x720";
  std::string path = "visbuf";
  std::string device = "auto";
  std::string cull = "occlusion";
  float lodError = 1.0f;
  bool noLod = false;
  std::string swRaster = "auto";  // auto | on | off (FrameOptions::swRaster); key M toggles on / off
  std::string shading = "auto";
  uint32_t drawCapacity = 0;
  bool wideIds = false;
  bool validation = false;        // the viewer's own instance: validation layer + counting messenger
  uint32_t framesInFlight = 2;    // RendererConfig::framesInFlight and the viewer's fences / semaphores
  std::string present = "fifo";   // fifo | mailbox
  std::string surface = "srgb";   // srgb | unorm (the swapchain format family)
  uint32_t frames = 0;            // exit after N presented frames; 0: when the window closes
  std::string screenshot;         // write the last frame's colour output here, then exit
  double time = 0.0;              // animation time (s)
  bool animate = false;           // play the animation
  std::string view = "shaded";    // shaded, or a debug view of render --view (key V cycles them)
};

void addViewCommand(CLI::App& app, ViewCommand& cmd);
int runView(const ViewCommand& cmd);

}  // namespace visbuf::tools
