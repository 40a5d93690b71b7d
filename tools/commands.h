// Subcommand declarations: each adds its options to the CLI and runs with the parsed values.
#pragma once

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
  std::string output = "visbuf.png";
  std::string idsOut;
  std::string json;
  bool reference = false;  // also render the forward path and report the error against it
  bool referenceFull = false;  // also render visbuf with no culling and no LOD and report the error against it
  std::string view = "shaded";  // debug view written to -o instead of the shaded image
  int pyramidLevel = -1;        // --view pyramid: the level to show
  bool freezeCulling = false;   // cull from the scene's default camera, then render --camera-pos with it
};

void addRenderCommand(CLI::App& app, RenderCommand& cmd);
int runRender(const RenderCommand& cmd);

// visbuf bake (tools/bake_command.cpp): glTF -> pack. Exit codes: 0 ok, 1 bad input, 2 usage.
struct BakeCommand {
  std::string input;                                   // .gltf / .glb
  std::string output;                                  // pack to write
  uint32_t lodCount = MeshBuildOptions{}.maxLods;      // LOD levels incl. the full mesh, 1..MAX_LODS
  uint32_t lodMinTriangles = MeshBuildOptions{}.minTriangles;
  bool quantize = false;                               // not implemented yet: usage error
  std::string json;                                    // summary as JSON; empty: none
};

void addBakeCommand(CLI::App& app, BakeCommand& cmd);
int runBake(const BakeCommand& cmd);

}  // namespace visbuf::tools
