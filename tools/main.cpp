// visbuf: command-line front end of the engine module. Subcommands live in their own files.
#include <cstdio>
#include <exception>
#include <new>

#include <CLI/CLI.hpp>

#include "cli_checks.h"
#include "commands.h"
#include "invocation.h"
#include "visbuf/core/version.h"

int main(int argc, char** argv) {
  visbuf::tools::setInvocation(argc, argv);
  CLI::App app{"visbuf: GPU-driven culling + visibility-buffer renderer (headless, Vulkan 1.3)"};
  app.set_version_flag("--version", "visbuf " + visbuf::versionString());
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
#ifdef VISBUF_HAVE_VIEW
  visbuf::tools::ViewCommand view;
  visbuf::tools::addViewCommand(app, view);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ValidationError& e) {
    app.exit(e);  // an option's value is not a number or out of its range: bad input, exit 1
    return 1;
  } catch (const CLI::ConversionError& e) {
    app.exit(e);
    return 1;
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help or the usage error
    return rc == 0 ? 0 : 2;      // a usage error (unknown option, missing argument) exits 2; success 0
  }
  // Nothing escapes as an abort: an allocation that fails (an input larger than the memory this process may
  // use) or any other exception is a clear error with exit code 1 (bad input).
  try {
    if (app.got_subcommand("render")) return visbuf::tools::runRender(render);
    if (app.got_subcommand("bake")) return visbuf::tools::runBake(bake);
    if (app.got_subcommand("bench")) return visbuf::tools::runBench(bench);
    if (app.got_subcommand("bench-bake")) return visbuf::tools::runBenchBake(benchBake);
    if (app.got_subcommand("stress")) return visbuf::tools::runStress(stress);
#ifdef VISBUF_HAVE_VIEW
    if (app.got_subcommand("view")) return visbuf::tools::runView(view);
#endif
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "visbuf: error (out of memory): an allocation failed: the input needs more memory than this process "
                 "may use (free memory, ulimit -v)\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "visbuf: error (internal): %s\n", visbuf::tools::printable(e.what()).c_str());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "visbuf: error (internal): an unknown exception\n");
    return 1;
  }
  return 2;
}
