// visbuf: command-line front end of the engine module. Subcommands live in their own files.
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "visbuf/gpu/check.h"
#include "cli_checks.h"
#include "commands.h"
#include "invocation.h"
#include "visbuf/core/file_read.h"
#include "visbuf/core/version.h"

namespace {

// Levenshtein distance, for "did you mean".
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The first argument when it is not an option nor a subcommand: "unknown subcommand 'rendr' (did you mean
// render?); the subcommands: ..." (CLI11 would only say that a subcommand is required). Empty when it is fine.
std::string unknownSubcommand(const CLI::App& app, int argc, char** argv) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App* a) { return !a->get_name().empty(); }))
    names.push_back(sub->get_name());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  if (argc < 2) return "a subcommand is required: " + list + " (visbuf SUBCOMMAND --help)";
  const std::string first = argv[1];
  if (!first.empty() && first[0] == '-') return {};  // an option: CLI11 reports it (--help, --version, unknown)
  for (const std::string& n : names)
    if (n == first) return {};
  std::string best;
  size_t bestDistance = 3;  // at most 2 edits, or a prefix
  for (const std::string& n : names) {
    const size_t d = editDistance(first, n);
    if (d < bestDistance || (best.empty() && !first.empty() && n.rfind(first, 0) == 0)) best = n, bestDistance = d;
  }
  return "unknown subcommand '" + visbuf::tools::printable(first) + "'" +
         (best.empty() ? std::string() : " (did you mean " + best + "?)") + "; the subcommands: " + list;
}

// A parse error's text (it quotes what was typed: an unknown option, a value) with control characters escaped.
int reportParseError(const CLI::ParseError& e, int code) {
  std::fprintf(stderr, "visbuf: error: %s\nRun with --help for more information.\n",
               visbuf::tools::printable(e.what()).c_str());
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  visbuf::tools::setInvocation(argc, argv);
  // One command a process: every file it reads is an input that no output of it may replace (core/file_read.h).
  visbuf::enableInputLog();
  CLI::App app{"visbuf: GPU-driven culling + visibility-buffer renderer (headless, Vulkan 1.3)"};
  app.set_version_flag("--version", "visbuf " + visbuf::versionString());
  app.require_subcommand(1);
  visbuf::tools::RenderCommand render;
  visbuf::tools::addRenderCommand(app, render);
  visbuf::tools::BakeCommand bake;
  visbuf::tools::addBakeCommand(app, bake);
  visbuf::tools::ExtensionsCommand extensions;
  visbuf::tools::addExtensionsCommand(app, extensions);
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
  if (const std::string unknown = unknownSubcommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "visbuf: error: %s\n", unknown.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ValidationError& e) {
    return reportParseError(e, 1);  // an option's value is not a number or out of its range: bad input, exit 1
  } catch (const CLI::ConversionError& e) {
    return reportParseError(e, 1);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --version
    return reportParseError(e, 2);  // a usage error (unknown option, missing argument) exits 2
  }
  // Nothing escapes as an abort: an allocation that fails (an input larger than the memory this process may
  // use) or any other exception is a clear error with exit code 1 (bad input).
  try {
    if (app.got_subcommand("render")) return visbuf::tools::runRender(render);
    if (app.got_subcommand("bake")) return visbuf::tools::runBake(bake);
    if (app.got_subcommand("extensions")) return visbuf::tools::runExtensions(extensions);
    if (app.got_subcommand("bench")) return visbuf::tools::runBench(bench);
    if (app.got_subcommand("bench-bake")) return visbuf::tools::runBenchBake(benchBake);
    if (app.got_subcommand("stress")) return visbuf::tools::runStress(stress);
#ifdef VISBUF_HAVE_VIEW
    if (app.got_subcommand("view")) return visbuf::tools::runView(view);
#endif
  } catch (const visbuf::gpu::VulkanFailure& f) {  // a Vulkan call of the tool's own (the library returns errors)
    const visbuf::Error e = visbuf::gpu::errorOf(f);
    std::fprintf(stderr, "visbuf: error (%s): %s\n", visbuf::errorCodeName(e.code), e.message.c_str());
    return 1;
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
