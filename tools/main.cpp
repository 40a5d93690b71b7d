// visbuf: command-line front end of the engine module. Subcommands live in their own files.
#include <cstdio>

#include <CLI/CLI.hpp>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"visbuf: GPU-driven culling + visibility-buffer renderer (headless, Vulkan 1.3)"};
  app.require_subcommand(1);
  visbuf::tools::RenderCommand render;
  visbuf::tools::addRenderCommand(app, render);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  if (app.got_subcommand("render")) return visbuf::tools::runRender(render);
  return 2;
}
