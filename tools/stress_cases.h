// The stress suite's named cases (tools/stress_cases.cpp), each with explicit pass/fail bounds, run by
// `visbuf stress` (tools/stress_command.cpp) in full or in the reduced form the test suite runs.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "visbuf/gpu/device.h"

namespace visbuf::tools {

struct StressContext {
  gpu::Device& device;
  bool reduced = false;  // the CI-sized variant: smaller images and scenes, fewer distances
  std::string assetsDir; // ../shared/assets when present (bad glTF inputs); empty: those rows are skipped
};

// One measured configuration of a case. `pass` is null for rows that only inform (no bound applies).
struct StressRow {
  nlohmann::ordered_json values;  // label first, then measurements, then "pass"
};

struct StressCase {
  std::string name;   // e.g. "far-from-origin"
  std::string what;   // one sentence: what is stressed
  std::string bound;  // the pass/fail rule, in words with its numbers
  std::vector<StressRow> rows;
  bool passed() const;
};

struct StressCaseInfo {
  std::string name;
  std::function<StressCase(const StressContext&)> run;
};

// Every case, in the order `visbuf stress` runs them.
const std::vector<StressCaseInfo>& stressCases();

}  // namespace visbuf::tools
