// visbuf: command-line front end of the engine module. Subcommands live in their own files.
#include <cstdio>

#include <CLI/CLI.hpp>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"visbuf: GPU-driven culling + visibility-buffer renderer (headless, Vulkan 1.3)"};
  app.require_subcommand(1);
  visbuf::tools::RenderCommand render;
  visbuf::tools::addRenderCommand(app, render);
  visbuf::tools::BakeCommand bake;
  visbuf::tools::addBakeCommand(app, bake);
  visbuf::tools::BenchCommand bench;
  visbuf::tools::addBenchCommand(app, bench, argc, argv);
  visbuf::tools::BenchBakeCommand benchBake;
  visbuf::tools::addBenchBakeCommand(app, benchBake, argc, argv);
  visbuf::tools::StressCommand stress;
  visbuf::tools::addStressCommand(app, stress, argc, argv);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help or the usage error
    return rc == 0 ? 0 : 2;      // every usage error exits 2 (bad input 1, success 0)
  }
  if (app.got_subcommand("render")) return visbuf::tools::runRender(render);
  if (app.got_subcommand("bake")) return visbuf::tools::runBake(bake);
  if (app.got_subcommand("bench")) return visbuf::tools::runBench(bench);
  if (app.got_subcommand("bench-bake")) return visbuf::tools::runBenchBake(benchBake);
  if (app.got_subcommand("stress")) return visbuf::tools::runStress(stress);
  return 2;
}
