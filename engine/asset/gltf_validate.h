// Internal to engine/asset: the schema check of a glTF JSON document that runs BEFORE tinygltf parses it.
// tinygltf narrows integers to int (node 4294967296 becomes node 0, a sparse byteOffset of 2^62 becomes 0)
// and silently drops optional properties of the wrong type ("translation": ["NaN", 0, 0], a negative
// bufferView); this check refuses those inputs with an error naming the JSON path instead.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "visbuf/core/result.h"

namespace visbuf::gltf_detail {

// Checks every property of glTF 2.0 core and of the extensions visbuf reads that is an index, a count, an
// offset, a length, a stride, an enum, a number or a number array (the table in gltf_validate.cpp):
//   - indices (glTFid): a JSON integer in [0, size of the array they index);
//   - counts, offsets, lengths: a JSON integer >= the spec's minimum and <= 2^53 (<= 2^31 - 1 where tinygltf
//     keeps the value in an int); they are checked against the real buffer sizes later, by the importer;
//   - byteStride: an integer multiple of 4 in [4, 252]; enums: one of the spec's values;
//   - numbers: finite JSON numbers; number arrays: the spec's element count, every element a finite number;
//     where the spec bounds a factor (the KHR_materials_* extensions' factors: [0,1], >= 0) the bound too;
//   - objects the spec requires (KHR_materials_unlit's empty object) are JSON objects;
//   - every object / array on the way to a checked property has that JSON type.
// `extras` subtrees and properties the table does not name are not looked at. MalformedInput naming
// "<file>: <json path>: <value> ..." on the first violation. `doc` must be a parsed JSON object.
Status validateGltfDocument(const nlohmann::json& doc, const std::string& file);

// One row of the table (exposed so that tests can break every rule).
struct GltfRule {
  enum class Kind {
    Index,     // glTFid into `collection` (a pattern; "#0": the index the first "[]" of the match took)
    Integer,   // count / offset / length / set index: a JSON integer in [min, max]
    Stride,    // bufferView.byteStride: a multiple of 4 in [4, 252]
    Enum,      // a JSON integer, one of `values`
    TextEnum,  // a string, one of `names`
    Text,      // a string
    Boolean,   // true / false
    Number,    // a finite number in [low, high]
    Numbers,   // an array of [min, max] finite numbers, each in [low, high]
    Object,    // a JSON object
  };
  std::string pattern;  // "nodes[].children[]": "[]" every array element, "{}" every object value
  Kind kind;
  std::string collection;
  int64_t min = 0, max = 0;
  std::vector<int64_t> values;
  std::vector<std::string> names;
  const char* what = "";  // Integer: "count", "byte offset", ...
  double low = -HUGE_VAL, high = HUGE_VAL;  // Number / Numbers: the spec's bounds of the value(s)
};
const std::vector<GltfRule>& gltfValidationRules();

}  // namespace visbuf::gltf_detail
