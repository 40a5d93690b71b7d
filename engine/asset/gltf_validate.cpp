// The schema check of a glTF document before tinygltf parses it (contract in gltf_validate.h). The rules are
// a table, read like the spec: (path pattern -> rule). A pattern is a dot-separated list of property names,
// each followed by any number of "[]" (every element of an array) and "{}" (every value of an object: the
// attribute maps). An Index rule names the array it indexes; "#0" in that name is the index the first "[]"
// of the matched path took (animations[#0].samplers: the samplers of the same animation).
#include "visbuf/asset/gltf_validate.h"

#include <cmath>
#include <cstdint>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "visbuf/asset/uri_resolver.h"

namespace visbuf::gltf_detail {
namespace {

using nlohmann::json;

using Kind = GltfRule::Kind;
using Rule = GltfRule;

constexpr int64_t kMax53 = int64_t{1} << 53;     // JSON's exact integers
constexpr int64_t kMaxInt = int64_t{0x7FFFFFFF};  // tinygltf holds the value in an int

// ---------------------------------------------------------------------------------------------------------
// The table.

std::vector<Rule> buildRules() {
  std::vector<Rule> r;
  auto add = [&](std::string p, Kind kind) -> Rule& {
    r.emplace_back();
    r.back().pattern = std::move(p);
    r.back().kind = kind;
    return r.back();
  };
  auto index = [&](std::string p, std::string collection) { add(std::move(p), Kind::Index).collection = collection; };
  auto integer = [&](std::string p, const char* what, int64_t min, int64_t max) {
    Rule& rule = add(std::move(p), Kind::Integer);
    rule.what = what;
    rule.min = min;
    rule.max = max;
  };
  auto count = [&](std::string p, int64_t min, int64_t max = kMax53) { integer(std::move(p), "count", min, max); };
  auto offset = [&](std::string p, int64_t max = kMax53) { integer(std::move(p), "byte offset", 0, max); };
  auto length = [&](std::string p) { integer(std::move(p), "byte length", 1, kMax53); };
  auto setIndex = [&](std::string p) { integer(std::move(p), "texture coordinate set", 0, kMaxInt); };
  auto oneOf = [&](std::string p, std::vector<int64_t> v) { add(std::move(p), Kind::Enum).values = std::move(v); };
  auto oneOfText = [&](std::string p, std::vector<std::string> v) {
    add(std::move(p), Kind::TextEnum).names = std::move(v);
  };
  auto text = [&](std::string p) { add(std::move(p), Kind::Text); };
  auto boolean = [&](std::string p) { add(std::move(p), Kind::Boolean); };
  auto number = [&](std::string p, double low = -HUGE_VAL, double high = HUGE_VAL) {
    Rule& rule = add(std::move(p), Kind::Number);
    rule.low = low;
    rule.high = high;
  };
  auto numbers = [&](std::string p, int64_t minItems, int64_t maxItems, double low = -HUGE_VAL,
                     double high = HUGE_VAL) {
    Rule& rule = add(std::move(p), Kind::Numbers);
    rule.min = minItems;
    rule.max = maxItems;
    rule.low = low;
    rule.high = high;
  };
  // textureInfo (and normal / occlusion textureInfo), with KHR_texture_transform.
  auto textureInfo = [&](const std::string& p) {
    index(p + ".index", "textures");
    setIndex(p + ".texCoord");
    number(p + ".scale");
    number(p + ".strength");
    const std::string t = p + ".extensions.KHR_texture_transform";
    numbers(t + ".offset", 2, 2);
    number(t + ".rotation");
    numbers(t + ".scale", 2, 2);
    setIndex(t + ".texCoord");
  };

  // Top level.
  index("scene", "scenes");
  text("extensionsUsed[]");
  text("extensionsRequired[]");
  text("asset.version");
  text("asset.minVersion");
  index("scenes[].nodes[]", "nodes");

  // Nodes.
  index("nodes[].camera", "cameras");
  index("nodes[].children[]", "nodes");
  index("nodes[].skin", "skins");
  index("nodes[].mesh", "meshes");
  numbers("nodes[].matrix", 16, 16);
  numbers("nodes[].rotation", 4, 4);
  numbers("nodes[].scale", 3, 3);
  numbers("nodes[].translation", 3, 3);
  numbers("nodes[].weights", 1, kMax53);
  index("nodes[].extensions.KHR_lights_punctual.light", "extensions.KHR_lights_punctual.lights");
  index("nodes[].extensions.EXT_mesh_gpu_instancing.attributes{}", "accessors");

  // Meshes.
  index("meshes[].primitives[].attributes{}", "accessors");
  index("meshes[].primitives[].indices", "accessors");
  index("meshes[].primitives[].material", "materials");
  oneOf("meshes[].primitives[].mode", {0, 1, 2, 3, 4, 5, 6});
  index("meshes[].primitives[].targets[]{}", "accessors");
  numbers("meshes[].weights", 1, kMax53);
  const std::string draco = "meshes[].primitives[].extensions.KHR_draco_mesh_compression";
  index(draco + ".bufferView", "bufferViews");
  integer(draco + ".attributes{}", "Draco attribute id", 0, kMaxInt);

  // Accessors (sparse: tinygltf keeps count and offsets in an int).
  index("accessors[].bufferView", "bufferViews");
  offset("accessors[].byteOffset");
  oneOf("accessors[].componentType", {5120, 5121, 5122, 5123, 5125, 5126});
  boolean("accessors[].normalized");
  count("accessors[].count", 1);
  oneOfText("accessors[].type", {"SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"});
  numbers("accessors[].max", 1, 16);
  numbers("accessors[].min", 1, 16);
  count("accessors[].sparse.count", 1, kMaxInt);
  index("accessors[].sparse.indices.bufferView", "bufferViews");
  offset("accessors[].sparse.indices.byteOffset", kMaxInt);
  oneOf("accessors[].sparse.indices.componentType", {5121, 5123, 5125});
  index("accessors[].sparse.values.bufferView", "bufferViews");
  offset("accessors[].sparse.values.byteOffset", kMaxInt);

  // Buffers and buffer views (EXT_meshopt_compression included).
  text("buffers[].uri");
  length("buffers[].byteLength");
  boolean("buffers[].extensions.EXT_meshopt_compression.fallback");
  index("bufferViews[].buffer", "buffers");
  offset("bufferViews[].byteOffset");
  length("bufferViews[].byteLength");
  add("bufferViews[].byteStride", Kind::Stride);
  oneOf("bufferViews[].target", {34962, 34963});
  const std::string meshopt = "bufferViews[].extensions.EXT_meshopt_compression";
  index(meshopt + ".buffer", "buffers");
  offset(meshopt + ".byteOffset");
  length(meshopt + ".byteLength");
  integer(meshopt + ".byteStride", "byte stride", 1, 256);
  count(meshopt + ".count", 1);
  // mode / filter: strings; a value this importer does not know is Unsupported there (a later revision's).
  text(meshopt + ".mode");
  text(meshopt + ".filter");

  // Cameras.
  oneOfText("cameras[].type", {"perspective", "orthographic"});
  for (const char* f : {"aspectRatio", "yfov", "zfar", "znear"}) number(std::string("cameras[].perspective.") + f);
  for (const char* f : {"xmag", "ymag", "zfar", "znear"}) number(std::string("cameras[].orthographic.") + f);

  // Images, samplers, textures.
  text("images[].uri");
  text("images[].mimeType");
  index("images[].bufferView", "bufferViews");
  oneOf("samplers[].magFilter", {9728, 9729});
  oneOf("samplers[].minFilter", {9728, 9729, 9984, 9985, 9986, 9987});
  oneOf("samplers[].wrapS", {33071, 33648, 10497});
  oneOf("samplers[].wrapT", {33071, 33648, 10497});
  index("textures[].sampler", "samplers");
  index("textures[].source", "images");
  for (const char* e : {"KHR_texture_basisu", "EXT_texture_webp", "EXT_texture_avif", "MSFT_texture_dds"})
    index(std::string("textures[].extensions.") + e + ".source", "images");

  // Materials (core and KHR_materials_*).
  const std::string pbr = "materials[].pbrMetallicRoughness";
  numbers(pbr + ".baseColorFactor", 4, 4);
  number(pbr + ".metallicFactor");
  number(pbr + ".roughnessFactor");
  textureInfo(pbr + ".baseColorTexture");
  textureInfo(pbr + ".metallicRoughnessTexture");
  textureInfo("materials[].normalTexture");
  textureInfo("materials[].occlusionTexture");
  textureInfo("materials[].emissiveTexture");
  numbers("materials[].emissiveFactor", 3, 3);
  // An unknown alphaMode stays the importer's: it is treated as OPAQUE with a warning naming it (gltf_materials.cpp).
  text("materials[].alphaMode");
  number("materials[].alphaCutoff");
  boolean("materials[].doubleSided");
  const std::string ext = "materials[].extensions.";
  // The extensions visbuf shades (factors bounded as their schemas say: a value outside is an error, unlike the
  // core factors, which are clamped with a warning for the exporters that write 1.0000001).
  add(ext + "KHR_materials_unlit", Kind::Object);
  number(ext + "KHR_materials_emissive_strength.emissiveStrength", 0.0);
  const std::string coat = ext + "KHR_materials_clearcoat.";
  number(coat + "clearcoatFactor", 0.0, 1.0);
  number(coat + "clearcoatRoughnessFactor", 0.0, 1.0);
  for (const char* t : {"clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"}) textureInfo(coat + t);
  const std::string specGloss = ext + "KHR_materials_pbrSpecularGlossiness.";
  numbers(specGloss + "diffuseFactor", 4, 4, 0.0, 1.0);
  numbers(specGloss + "specularFactor", 3, 3, 0.0, 1.0);
  number(specGloss + "glossinessFactor", 0.0, 1.0);
  for (const char* t : {"diffuseTexture", "specularGlossinessTexture"}) textureInfo(specGloss + t);
  // Extensions visbuf does not shade (the extension table warns): their values are still checked for shape.
  struct MaterialExt {
    const char* name;
    std::vector<const char*> numbers, colors3, textures;
  };
  const MaterialExt materialExts[] = {
      {"KHR_materials_ior", {"ior"}, {}, {}},
      {"KHR_materials_dispersion", {"dispersion"}, {}, {}},
      {"KHR_materials_transmission", {"transmissionFactor"}, {}, {"transmissionTexture"}},
      {"KHR_materials_volume", {"thicknessFactor", "attenuationDistance"}, {"attenuationColor"}, {"thicknessTexture"}},
      {"KHR_materials_sheen", {"sheenRoughnessFactor"}, {"sheenColorFactor"}, {"sheenColorTexture", "sheenRoughnessTexture"}},
      {"KHR_materials_specular", {"specularFactor"}, {"specularColorFactor"}, {"specularTexture", "specularColorTexture"}},
      {"KHR_materials_iridescence",
       {"iridescenceFactor", "iridescenceIor", "iridescenceThicknessMinimum", "iridescenceThicknessMaximum"}, {},
       {"iridescenceTexture", "iridescenceThicknessTexture"}},
      {"KHR_materials_anisotropy", {"anisotropyStrength", "anisotropyRotation"}, {}, {"anisotropyTexture"}},
  };
  for (const MaterialExt& m : materialExts) {
    const std::string base = ext + m.name + ".";
    for (const char* f : m.numbers) number(base + f);
    for (const char* f : m.colors3) numbers(base + f, 3, 3);
    for (const char* f : m.textures) textureInfo(base + f);
  }

  // Skins and animations.
  index("skins[].inverseBindMatrices", "accessors");
  index("skins[].skeleton", "nodes");
  index("skins[].joints[]", "nodes");
  index("animations[].channels[].sampler", "animations[#0].samplers");
  index("animations[].channels[].target.node", "nodes");
  text("animations[].channels[].target.path");  // (the importer names an unknown path or interpolation itself)
  index("animations[].samplers[].input", "accessors");
  index("animations[].samplers[].output", "accessors");
  text("animations[].samplers[].interpolation");

  // KHR_lights_punctual.
  const std::string lights = "extensions.KHR_lights_punctual.lights[]";
  text(lights + ".type");  // an unknown type is skipped with a warning (a later revision's light)
  numbers(lights + ".color", 3, 3);
  number(lights + ".intensity");
  number(lights + ".range");
  number(lights + ".spot.innerConeAngle");
  number(lights + ".spot.outerConeAngle");
  return r;
}


// ---------------------------------------------------------------------------------------------------------
// The walk.

// One step of a pattern: a property name and the "[]" / "{}" that follow it.
struct Step {
  std::string_view name;
  std::string_view each;  // e.g. "[]{}"
};

std::vector<Step> parsePattern(std::string_view pattern) {
  std::vector<Step> steps;
  size_t start = 0;
  while (start <= pattern.size()) {
    size_t end = pattern.find('.', start);
    if (end == std::string_view::npos) end = pattern.size();
    std::string_view segment = pattern.substr(start, end - start);
    const size_t bracket = segment.find_first_of("[{");
    steps.push_back({segment.substr(0, bracket),
                     bracket == std::string_view::npos ? std::string_view() : segment.substr(bracket)});
    start = end + 1;
  }
  return steps;
}

const char* typeName(const json& v) {
  switch (v.type()) {
    case json::value_t::object: return "an object";
    case json::value_t::array: return "an array";
    case json::value_t::string: return "a string";
    case json::value_t::boolean: return "a boolean";
    case json::value_t::null: return "null";
    case json::value_t::number_float: return "a fractional number";
    default: return "an integer";
  }
}

// The value as JSON text, escaped and cut short, for messages.
std::string shown(const json& v) {
  return quoteForMessage(v.dump(-1, ' ', false, json::error_handler_t::replace), 60);
}

class Walker {
 public:
  Walker(const json& doc, const std::string& file) : doc_(doc), file_(file) {}

  Status run(const Rule& rule) {
    rule_ = &rule;
    steps_ = parsePattern(rule.pattern);
    path_.clear();
    captures_.clear();
    return walkStep(doc_, 0);
  }

 private:
  Error fail(const std::string& message) const {
    return makeError(ErrorCode::MalformedInput, file_ + ": " + pathText() + ": " + message);
  }
  std::string pathText() const {
    std::string out;
    for (const std::string& part : path_) {
      if (!out.empty() && part[0] != '[') out += '.';
      out += part;
    }
    return out;
  }

  // `node` holds the property of step `i`.
  Status walkStep(const json& node, size_t i) {
    if (!node.is_object()) return fail("expected an object, found " + std::string(typeName(node)));
    const Step& step = steps_[i];
    auto it = node.find(std::string(step.name));
    if (it == node.end()) return {};
    path_.emplace_back(step.name);
    Status s = walkEach(*it, i, step.each);
    path_.pop_back();
    return s;
  }

  // `value` is step i's property; `each` the "[]" / "{}" still to expand.
  Status walkEach(const json& value, size_t i, std::string_view each) {
    if (each.empty()) return i + 1 == steps_.size() ? check(value) : walkStep(value, i + 1);
    const std::string_view rest = each.substr(2);
    if (each[0] == '[') {
      if (!value.is_array()) return fail("expected an array, found " + std::string(typeName(value)));
      for (size_t k = 0; k < value.size(); ++k) {
        path_.push_back("[" + std::to_string(k) + "]");
        captures_.push_back(k);
        Status s = walkEach(value[k], i, rest);
        captures_.pop_back();
        path_.pop_back();
        if (!s) return s;
      }
      return {};
    }
    if (!value.is_object()) return fail("expected an object, found " + std::string(typeName(value)));
    for (auto it = value.begin(); it != value.end(); ++it) {
      path_.push_back(quoteForMessage(it.key(), 60));
      Status s = walkEach(it.value(), i, rest);
      path_.pop_back();
      if (!s) return s;
    }
    return {};
  }

  // The array an Index rule indexes (null when absent or not an array).
  const json* collection() const {
    const json* node = &doc_;
    for (const Step& step : parsePattern(rule_->collection)) {
      if (!node->is_object()) return nullptr;
      auto it = node->find(std::string(step.name));
      if (it == node->end()) return nullptr;
      node = &*it;
      if (step.each.empty()) continue;
      // "[#k]": the k-th captured index of the matched path.
      const size_t k = static_cast<size_t>(step.each[2] - '0');
      if (!node->is_array() || k >= captures_.size() || captures_[k] >= node->size()) return nullptr;
      node = &(*node)[captures_[k]];
    }
    return node->is_array() ? node : nullptr;
  }

  // The integer of an integer JSON value clamped into int64 (a uint64 above INT64_MAX reads INT64_MAX: every
  // rule's maximum is far below).
  static int64_t integerOf(const json& v) {
    if (v.is_number_unsigned()) {
      const uint64_t u = v.get<uint64_t>();
      return u > uint64_t{INT64_MAX} ? INT64_MAX : static_cast<int64_t>(u);
    }
    return v.get<int64_t>();
  }

  Status check(const json& v) {
    const Rule& rule = *rule_;
    switch (rule.kind) {
      case Kind::Index: {
        const json* array = collection();
        const uint64_t size = array ? array->size() : 0;
        std::string into = rule.collection;
        if (size_t at = into.find("#0"); at != std::string::npos && !captures_.empty())
          into.replace(at, 2, std::to_string(captures_[0]));
        const std::string has = array ? "; " + into + " has " + std::to_string(size) + (size == 1 ? " entry" : " entries")
                                      : "; the file has no " + into;
        if (!v.is_number_integer()) return fail(shown(v) + " is not a valid index (not an integer)");
        const int64_t n = integerOf(v);
        if (n < 0 || static_cast<uint64_t>(n) >= size) return fail(shown(v) + " is not a valid index" + has);
        return {};
      }
      case Kind::Integer: {
        const std::string range = " (an integer from " + std::to_string(rule.min) + " to " +
                                  std::to_string(rule.max) + ")";
        if (!v.is_number_integer() || integerOf(v) < rule.min || integerOf(v) > rule.max)
          return fail(shown(v) + " is not a valid " + rule.what + range);
        return {};
      }
      case Kind::Stride: {
        const bool ok = v.is_number_integer() && integerOf(v) >= 4 && integerOf(v) <= 252 && integerOf(v) % 4 == 0;
        if (!ok) return fail(shown(v) + " is not a valid byte stride (a multiple of 4 from 4 to 252)");
        return {};
      }
      case Kind::Enum: {
        if (v.is_number_integer())
          for (int64_t allowed : rule.values)
            if (integerOf(v) == allowed) return {};
        std::string list;
        for (int64_t allowed : rule.values) list += (list.empty() ? "" : ", ") + std::to_string(allowed);
        return fail(shown(v) + " is not one of " + list);
      }
      case Kind::TextEnum: {
        if (v.is_string())
          for (const std::string& allowed : rule.names)
            if (v.get_ref<const std::string&>() == allowed) return {};
        std::string list;
        for (const std::string& allowed : rule.names) list += (list.empty() ? "\"" : ", \"") + allowed + "\"";
        return fail(shown(v) + " is not one of " + list);
      }
      case Kind::Text:
        if (!v.is_string()) return fail("expected a string, found " + std::string(typeName(v)));
        return {};
      case Kind::Boolean:
        if (!v.is_boolean()) return fail("expected true or false, found " + std::string(typeName(v)));
        return {};
      case Kind::Number:
        return checkNumber(v);
      case Kind::Object:
        if (!v.is_object()) return fail("expected an object, found " + std::string(typeName(v)));
        return {};
      case Kind::Numbers: {
        if (!v.is_array()) return fail("expected an array of numbers, found " + std::string(typeName(v)));
        const auto n = static_cast<int64_t>(v.size());
        if (n < rule.min || n > rule.max) {
          const std::string want = rule.min == rule.max ? std::to_string(rule.min)
                                   : rule.max == kMax53 ? "at least " + std::to_string(rule.min)
                                                        : std::to_string(rule.min) + " to " + std::to_string(rule.max);
          return fail("has " + std::to_string(n) + " elements, expected " + want);
        }
        for (size_t k = 0; k < v.size(); ++k) {
          path_.push_back("[" + std::to_string(k) + "]");
          Status s = checkNumber(v[k]);
          path_.pop_back();
          if (!s) return s;
        }
        return {};
      }
    }
    return {};
  }

  Status checkNumber(const json& v) const {
    if (!v.is_number()) return fail(shown(v) + " is not a number");
    if (v.is_number_float() && !std::isfinite(v.get<double>())) return fail(shown(v) + " is not a finite number");
    const double x = v.get<double>();
    if (x < rule_->low || x > rule_->high) {
      const std::string range = rule_->high == HUGE_VAL ? " (must be >= " + fmtNumber(rule_->low) + ")"
                                                         : " (must be in [" + fmtNumber(rule_->low) + ", " +
                                                               fmtNumber(rule_->high) + "])";
      return fail(shown(v) + " is out of range" + range);
    }
    return {};
  }
  static std::string fmtNumber(double x) {
    std::string s = std::to_string(x);
    while (s.size() > 1 && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  }

  const json& doc_;
  const std::string& file_;
  const Rule* rule_ = nullptr;
  std::vector<Step> steps_;
  std::vector<std::string> path_;
  std::vector<size_t> captures_;
};

}  // namespace

const std::vector<GltfRule>& gltfValidationRules() {
  static const std::vector<GltfRule> table = buildRules();
  return table;
}

Status validateGltfDocument(const nlohmann::json& doc, const std::string& file) {
  Walker walker(doc, file);
  for (const Rule& rule : gltfValidationRules())
    if (Status s = walker.run(rule); !s) return s;
  return {};
}

}  // namespace visbuf::gltf_detail
