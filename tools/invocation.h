// What every machine-readable output records about the run that wrote it: the visbuf version, the
// command line as typed (shell-quoted, so it can be pasted back), and the device.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace visbuf::tools {

// Called once by main() with the process arguments.
void setInvocation(int argc, char** argv);
// The whole command line, each argument shell-quoted where needed ("" before setInvocation).
const std::string& commandLine();
// `s` as one shell word: unchanged when it is plain, else in single quotes.
std::string shellQuote(const std::string& s);
// Adds "version", "command" and "device" to a JSON output (device: the Vulkan device's name, or a
// note that the command used none).
void stampInvocation(nlohmann::json& j, const std::string& device);
void stampInvocation(nlohmann::ordered_json& j, const std::string& device);

}  // namespace visbuf::tools
