// visbuf extensions: the glTF extensions visbuf knows and what it does with each (gltf_extensions.h), as text or
// as the Markdown table docs/gltf.md carries (a test keeps the two equal).

#include <cstdio>
#include <string>

#include "commands.h"
#include "visbuf/asset/gltf_extensions.h"

namespace visbuf::tools {
namespace {

const char* supportName(GltfExtensionSupport s) {
  switch (s) {
    case GltfExtensionSupport::Read: return "read";
    case GltfExtensionSupport::Partial: return "partial";
    case GltfExtensionSupport::Dropped: return "dropped";
  }
  return "?";
}

}  // namespace

void addExtensionsCommand(CLI::App& app, ExtensionsCommand& cmd) {
  CLI::App* sub = app.add_subcommand(
      "extensions", "list the glTF extensions visbuf knows: read, read in part, or dropped with a warning (a file "
                    "that requires one not read is refused by name)");
  sub->add_flag("--markdown", cmd.markdown, "print the table docs/gltf.md carries");
}

int runExtensions(const ExtensionsCommand& cmd) {
  if (cmd.markdown) {
    std::printf("| extension | support | what visbuf does | what is dropped |\n|---|---|---|---|\n");
  }
  for (const GltfExtension& e : gltfExtensions()) {
    const std::string effect(e.effect.empty() ? "-" : e.effect);
    const std::string dropped(e.dropped.empty() ? "-" : e.dropped);
    if (cmd.markdown) {
      std::printf("| `%.*s` | %s | %s | %s |\n", int(e.name.size()), e.name.data(), supportName(e.support),
                  effect.c_str(), dropped.c_str());
    } else {
      std::string what = e.effect.empty() ? "" : std::string(e.effect);
      if (!e.dropped.empty()) what += (what.empty() ? "dropped: " : "; dropped: ") + std::string(e.dropped);
      std::printf("%-42.*s %-8s %s\n", int(e.name.size()), e.name.data(), supportName(e.support), what.c_str());
    }
  }
  return 0;
}

}  // namespace visbuf::tools
