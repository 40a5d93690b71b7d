// visbuf stress: numerical stability and scale, as named cases with explicit bounds (tools/stress_cases.cpp).
// Writes stress.json and stress.md (atomically) to the output folder; exit 0 when every bound holds, 1 when one
// fails (or on bad input), 2 on usage errors, 3 when validation layers reported anything.
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include <fmt/format.h>

#include "cli_checks.h"
#include "commands.h"
#include "stats_output.h"
#include "stress_cases.h"
#include "visbuf/core/version.h"

namespace visbuf::tools {

void addStressCommand(CLI::App& app, StressCommand& c, int argc, char** argv) {
  for (int i = 0; i < argc; ++i) c.commandLine += (i ? " " : "") + std::string(argv[i]);
  CLI::App* sub = app.add_subcommand("stress", "numerical stability and scale: named cases with pass/fail bounds");
  std::vector<std::string> names;
  for (const auto& info : stressCases()) names.push_back(info.name);
  sub->add_option("--case", c.cases, "cases to run (default: all)")->delimiter(',')->check(CLI::IsMember(names));
  sub->add_flag("--reduced", c.reduced, "the CI-sized variant (smaller images and scenes)");
  sub->add_option("--device", c.device, "auto | cpu | gpu | N")->capture_default_str();
  sub->add_flag("--validation", c.validation, "enable Vulkan validation layers (any message fails the run)");
  sub->add_option("--assets", c.assets, "shared assets folder (malformed glTF inputs); empty: skip them")
      ->capture_default_str();
  sub->add_option("-o,--output", c.output, "output folder (stress.json, stress.md)")->capture_default_str();
}

namespace {

std::string cell(const nlohmann::ordered_json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "**NO**";
  if (v.is_string()) {
    std::string s = v.get<std::string>();
    for (char& ch : s)
      if (ch == '|' || ch == '\n') ch = ' ';
    return s;
  }
  if (v.is_number_float()) {
    const double d = v.get<double>();
    if (std::isinf(d)) return "inf";
    return d != 0.0 && (std::abs(d) < 1e-2 || std::abs(d) >= 1e6) ? fmt::format("{:.2e}", d) : fmt::format("{:.4g}", d);
  }
  return v.dump();
}

std::string markdown(const std::vector<StressCase>& cases, const std::string& device, const std::string& command) {
  std::string md = fmt::format("Device: {}. Command: `{}`\n", device, command);
  for (const StressCase& c : cases) {
    md += fmt::format("\n### {} — {}\n\n{}.\n\nBound: {}.\n\n", c.name, c.passed() ? "pass" : "FAIL", c.what, c.bound);
    std::vector<std::string> keys;  // union of the rows' keys, in first-seen order
    for (const StressRow& r : c.rows)
      for (auto it = r.values.begin(); it != r.values.end(); ++it)
        if (std::find(keys.begin(), keys.end(), it.key()) == keys.end()) keys.push_back(it.key());
    std::string header = "|", rule = "|";
    for (const auto& k : keys) {
      header += fmt::format(" {} |", k);
      rule += "---|";
    }
    md += header + "\n" + rule + "\n";
    for (const StressRow& r : c.rows) {
      std::string line = "|";
      for (const auto& k : keys) line += fmt::format(" {} |", r.values.contains(k) ? cell(r.values[k]) : std::string());
      md += line + "\n";
    }
  }
  return md;
}

}  // namespace

int runStress(const StressCommand& c) {
  auto devOptions = gpu::parseDeviceOption(c.device);
  if (!devOptions) {
    std::fprintf(stderr, "visbuf stress: %s\n", printable(devOptions.error().message).c_str());
    return 2;
  }
  devOptions->validation = c.validation;
  // The output folder before any work (bad input, exit 1): it exists and is writable, or can be created.
  if (Status s = checkOutputFolder("-o", c.output); !s) {
    std::fprintf(stderr, "visbuf stress: error: %s\n", printable(s.error().message).c_str());
    return 1;
  }
  {
    const std::filesystem::path outFolder(c.output);
    if (Status s = checkOutputs({{"-o", (outFolder / "stress.json").string(), true},
                                 {"-o", (outFolder / "stress.md").string(), true}});
        !s) {
      std::fprintf(stderr, "visbuf stress: error: %s\n", printable(s.error().message).c_str());
      return 1;
    }
  }
  std::error_code ec;
  std::filesystem::create_directories(c.output, ec);
  if (ec) {
    std::fprintf(stderr, "visbuf stress: %s: cannot create the output folder\n", printable(c.output).c_str());
    return 1;
  }
  auto device = gpu::Device::create(*devOptions);
  if (!device) {
    std::fprintf(stderr, "visbuf stress: error: %s\n", printable(device.error().message, true).c_str());
    return 1;
  }
  StressContext ctx{**device, c.reduced, c.assets};
  std::vector<StressCase> results;
  nlohmann::ordered_json json = {{"version", versionString()}, {"command", c.commandLine}, {"device", (*device)->name()}, {"reduced", c.reduced}};
  for (const auto& info : stressCases()) {
    if (!c.cases.empty() && std::find(c.cases.begin(), c.cases.end(), info.name) == c.cases.end()) continue;
    const auto t0 = std::chrono::steady_clock::now();
    results.push_back(info.run(ctx));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const StressCase& r = results.back();
    std::printf("%-16s %s  (%zu rows, %.1f s)\n", r.name.c_str(), r.passed() ? "pass" : "FAIL", r.rows.size(), s);
    for (const StressRow& row : r.rows)
      if (row.values.contains("pass") && row.values["pass"].is_boolean() && !row.values["pass"].get<bool>())
        std::printf("    failed: %s\n", row.values.dump().c_str());
    nlohmann::ordered_json cj = {{"name", r.name}, {"what", r.what}, {"bound", r.bound}, {"pass", r.passed()},
                                 {"seconds", s},   {"rows", nlohmann::ordered_json::array()}};
    for (const StressRow& row : r.rows) cj["rows"].push_back(row.values);
    json["cases"].push_back(cj);
  }
  bool all = true;
  for (const StressCase& r : results) all = all && r.passed();
  const uint32_t messages = (*device)->validationMessages();
  json["validationMessages"] = messages;
  json["pass"] = all && messages == 0;
  const std::filesystem::path out(c.output);
  for (Status st : {writeTextFile((out / "stress.json").string(), json.dump(2) + "\n"),
                    writeTextFile((out / "stress.md").string(), markdown(results, (*device)->name(), c.commandLine))})
    if (!st) {
      std::fprintf(stderr, "visbuf stress: %s\n", printable(st.error().message).c_str());
      return 1;
    }
  std::printf("visbuf stress: %s; wrote %s/stress.json and stress.md\n", all ? "every bound holds" : "BOUNDS FAILED",
              printable(c.output).c_str());
  if (messages) {
    std::fprintf(stderr, "visbuf stress: %u validation messages\n", messages);
    return 3;
  }
  return all ? 0 : 1;
}

}  // namespace visbuf::tools
