#include "invocation.h"

#include "visbuf/core/version.h"

namespace visbuf::tools {

namespace {
std::string gCommandLine;

template <class Json>
void stamp(Json& j, const std::string& device) {
  j["version"] = versionString();
  j["command"] = gCommandLine;
  j["device"] = device;
}
}  // namespace

std::string shellQuote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=./,:@%") ==
                        std::string::npos)
    return s;
  std::string out = "'";
  for (char ch : s) out += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return out + "'";
}

void setInvocation(int argc, char** argv) {
  gCommandLine.clear();
  for (int i = 0; i < argc; ++i) gCommandLine += (i ? " " : "") + shellQuote(argv[i]);
}

const std::string& commandLine() { return gCommandLine; }

void stampInvocation(nlohmann::json& j, const std::string& device) { stamp(j, device); }
void stampInvocation(nlohmann::ordered_json& j, const std::string& device) { stamp(j, device); }

}  // namespace visbuf::tools
