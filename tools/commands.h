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
};

void addRenderCommand(CLI::App& app, RenderCommand& cmd);
int runRender(const RenderCommand& cmd);

}  // namespace visbuf::tools
