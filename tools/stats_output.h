// Human-readable stats block and JSON for FrameStats.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "visbuf/core/result.h"
#include "visbuf/render/renderer.h"
#include "visbuf/render/scene_motion.h"

namespace visbuf::tools {

std::string formatStats(const FrameStats& stats);
nlohmann::json statsToJson(const FrameStats& stats);
// --moving / --churn: one frame's scene changes (SceneMotion) beside its upload and culling counters, and the
// summary line of a run.
nlohmann::json motionFrameJson(const SceneMotionFrame& changes, const FrameStats& stats);
std::string formatMotion(const nlohmann::json& perFrame, uint32_t movingObjects);
// Atomic writes (temporary file in the same folder + rename).
Status writeTextFile(const std::string& path, const std::string& text);
Status writeJsonFile(const std::string& path, const nlohmann::json& json);

}  // namespace visbuf::tools
