// Human-readable stats block and JSON for FrameStats.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "visbuf/core/result.h"
#include "visbuf/render/renderer.h"

namespace visbuf::tools {

std::string formatStats(const FrameStats& stats);
nlohmann::json statsToJson(const FrameStats& stats);
// Atomic writes (temporary file in the same folder + rename).
Status writeTextFile(const std::string& path, const std::string& text);
Status writeJsonFile(const std::string& path, const nlohmann::json& json);

}  // namespace visbuf::tools
