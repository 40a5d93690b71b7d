// bakeTextures (texture_bake.h): which images a scene's materials use, baking them in parallel within the memory
// gate, dropping the undecodable ones, and the texture classes. The per-image steps are in texture_bake.cpp.

#include "visbuf/asset/texture_bake.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <bit>
#include <map>
#include <mutex>
#include <optional>
#include <tuple>
#include <utility>

#include "visbuf/asset/texture_decode.h"
#include "visbuf/asset/uri_resolver.h"
#include "visbuf/core/file_read.h"
#include "visbuf/shared/config.h"

namespace visbuf {

namespace {

constexpr uint32_t kMaxTextureSize = kMaxBakedTextureSize;
constexpr uint32_t kMaxLayersPerClass = kMaxTextureClassLayers;

// A texture to bake: one (image, colour space) pair and the slots that use it.
struct TextureKey {
  int32_t image = -1;
  ColorSpace colorSpace = ColorSpace::Linear;
  TextureSlotMask slots = 0;
};

// Numbers the (image, colour space) pairs in order of first use and points every reference at its number.
Result<std::vector<TextureKey>> assignTextures(size_t imageCount, Scene* scene) {
  std::vector<TextureKey> keys;
  std::map<std::pair<int32_t, ColorSpace>, int32_t> index;
  for (Material& m : scene->materials) {
    const auto slots = textureSlots(m);
    for (size_t slot = 0; slot < slots.size(); ++slot) {
      TextureRef* ref = slots[slot];
      const ColorSpace colorSpace = textureSlotColorSpace(slot);
      if (ref->image < 0) continue;
      if (size_t(ref->image) >= imageCount) {
        return makeError(ErrorCode::MalformedInput,
                         fmt::format("material '{}': image {} does not exist ({} images)", m.name, ref->image,
                                     imageCount));
      }
      auto [it, added] = index.emplace(std::pair{ref->image, colorSpace}, int32_t(keys.size()));
      if (added) keys.push_back({ref->image, colorSpace, 0});
      keys[size_t(it->second)].slots |= TextureSlotMask{1} << slot;
      ref->baked = it->second;
    }
  }
  return keys;
}

bool droppable(const Error& e, const TextureBakeOptions& options) {
  return options.dropUndecodableImages &&
         (e.code == ErrorCode::MalformedInput || e.code == ErrorCode::FileNotFound);
}

// Removes the textures whose image failed droppably (droppable()) from `keys`, `results` and `formats`, clears
// every material slot that referenced them and renumbers the others' `baked`; one warning per dropped image.
void dropUndecodedTextures(Scene* scene, std::vector<TextureKey>& keys,
                           std::vector<std::optional<Result<BakedImage>>>& results,
                           std::vector<TextureFormat>& formats, TextureBakeReport* report) {
  std::vector<int32_t> renumber(keys.size(), -1);
  size_t kept = 0;
  for (size_t t = 0; t < keys.size(); ++t) {
    if (*results[t]) {
      renumber[t] = int32_t(kept);
      if (kept != t) {
        keys[kept] = keys[t];
        results[kept] = std::move(results[t]);
        formats[kept] = formats[t];
      }
      ++kept;
      continue;
    }
    if (report) {
      report->warnings.push_back(fmt::format("{}; its texture is dropped from the materials that use it",
                                             results[t]->error().message));
    }
  }
  if (kept == keys.size()) return;
  keys.resize(kept);
  results.resize(kept);
  formats.resize(kept);
  for (Material& m : scene->materials) {
    for (TextureRef* ref : textureSlots(m)) {
      if (ref->image < 0) continue;
      ref->baked = renumber[size_t(ref->baked)];
      if (ref->baked < 0) *ref = TextureRef{};
    }
  }
}

// Puts each baked image into a class (layer = position in its class) and concatenates the texels mip-major.
void buildClasses(std::vector<BakedImage>& baked, Scene* scene) {
  // (size, colour space, format) -> class with room
  std::map<std::tuple<uint32_t, ColorSpace, TextureFormat>, uint32_t> open;
  for (size_t t = 0; t < baked.size(); ++t) {
    Texture& texture = scene->textures[t];
    const auto key = std::tuple{baked[t].size, texture.colorSpace, baked[t].format};
    auto it = open.find(key);
    if (it == open.end() || scene->textureClasses[it->second].layers == kMaxLayersPerClass) {
      TextureClass c;
      c.size = baked[t].size;
      c.colorSpace = texture.colorSpace;
      c.format = baked[t].format;
      c.mipCount = TextureClass::mipCountFor(c.size);
      scene->textureClasses.push_back(c);
      it = open.insert_or_assign(key, uint32_t(scene->textureClasses.size() - 1)).first;
    }
    texture.sizeClass = it->second;
    texture.layer = scene->textureClasses[it->second].layers++;
  }
  for (uint32_t c = 0; c < scene->textureClasses.size(); ++c) {
    TextureClass& cls = scene->textureClasses[c];
    cls.texels.reserve(cls.totalBytes());
    for (uint32_t mip = 0; mip < cls.mipCount; ++mip) {
      for (size_t t = 0; t < baked.size(); ++t) {
        if (scene->textures[t].sizeClass != c) continue;  // textures are in layer order within a class
        std::vector<uint8_t>& level = baked[t].mips[mip];
        cls.texels.insert(cls.texels.end(), level.begin(), level.end());
        std::vector<uint8_t>().swap(level);
      }
    }
  }
}

}  // namespace

Status bakeTextures(const ImportedScene& imported, const TextureBakeOptions& options, Scene* scene,
                    TextureBakeReport* report, const TextureBakeProgress& progress) {
  if (options.maxTextureSize < 1 || options.maxTextureSize > kMaxTextureSize ||
      !std::has_single_bit(options.maxTextureSize)) {
    return makeError(ErrorCode::InvalidArgument, fmt::format("maxTextureSize {} must be a power of two in [1, {}]",
                                                             options.maxTextureSize, kMaxTextureSize));
  }
  if (options.maxImagePixels < 1 || (options.maxNormalMapSize != 0 && !std::has_single_bit(options.maxNormalMapSize)))
    return makeError(ErrorCode::InvalidArgument, "maxImagePixels must be >= 1, maxNormalMapSize 0 or a power of two");
  scene->textures.clear();
  scene->textureClasses.clear();
  std::vector<ImportedImage> derived;  // converted spec-gloss textures: image imported.images.size() + i
  std::vector<std::string> conversionNotes;
  if (Status s = convertSpecGlossTextures(imported, options, scene, &derived, &conversionNotes); !s) return s;
  if (report) report->notes.insert(report->notes.end(), conversionNotes.begin(), conversionNotes.end());
  const auto imageAt = [&](int32_t i) -> const ImportedImage& {
    const size_t n = imported.images.size();
    return size_t(i) < n ? imported.images[size_t(i)] : derived[size_t(i) - n];
  };
  auto keys = assignTextures(imported.images.size() + derived.size(), scene);
  if (!keys) return keys.error();
  // Images in parallel (each one's levels in parallel too: oneTBB nests); messages, textures and classes are
  // assembled afterwards in key order, so the result is that of a serial bake. After a failure, images behind
  // the first failed one are skipped: the error reported is the one a serial bake stops at.
  const size_t count = keys->size();
  std::vector<std::optional<Result<BakedImage>>> results(count);
  std::vector<TextureFormat> formats(count, TextureFormat::Rgba8);
  std::atomic<size_t> firstFailed{count};
  std::mutex progressMutex;
  size_t done = 0;
  ImageMemoryGate gate(kImageBakeMemoryBudget);  // images baked at once: within the budget (texture_decode.h)
  tbb::parallel_for(size_t{0}, count, [&](size_t t) {
    if (t > firstFailed.load()) return;
    const TextureKey& key = (*keys)[t];
    const ImportedImage& image = imageAt(key.image);
    const std::string name =
        fmt::format("{}: image {} '{}'", quoteForMessage(imported.name), key.image, quoteForMessage(image.name));
    Result<BakedImage> b = [&]() -> Result<BakedImage> {
      if (!image.rgba8.empty())  // (a derived image: decoded already)
        return bakeDecodedImage({image.width, image.height, image.rgba8, {}}, name, key.colorSpace,
                                options.maxTextureSize);
      // Memory: the file's bytes are reserved while it is read, then with the estimate of its bake
      // (imageBakePeakBytes); released and reserved again, never held while waiting for more.
      uint64_t fileBytes = image.bytes.size();  // embedded: copied below
      if (!image.path.empty()) (void)probeFile(image.path, &fileBytes, /*noFollow=*/true);
      fileBytes = std::min(fileBytes, kMaxImageFileBytes);
      gate.acquire(fileBytes);
      Result<std::vector<uint8_t>> file = image.path.empty() ? Result<std::vector<uint8_t>>(image.bytes)
                                                             : readImageFile(image);
      gate.release(fileBytes);
      if (!file) return makeError(file.error().code, imported.name + ": " + file.error().message);
      Result<ImageHeader> header = readImageHeader(file->data(), file->size(), name);
      // An image over the pixel budget is refused before anything of its size is allocated: reserve nothing.
      const bool admitted =
          header && uint64_t(header->width) * header->height <= options.maxImagePixels;
      const uint64_t reserved = file->size() + (admitted ? imageBakePeakBytes(*header, options.maxTextureSize) : 0);
      gate.acquire(reserved);
      // Isolated: while this thread waits inside the bake's nested parallel loops it must not start another
      // image, whose acquire() could wait on this one's reservation.
      Result<BakedImage> r = tbb::this_task_arena::isolate([&] {
        return bakeImage(file->data(), file->size(), name, key.colorSpace, options.maxTextureSize,
                         options.maxImagePixels);
      });
      gate.release(reserved);
      if (r && key.slots == kNormalSlotMask && options.maxNormalMapSize != 0 && options.maxNormalMapSize < r->size) {
        // The level of that size and those below it, as a larger source's cap keeps them (box-filtered mips).
        r->mips.erase(r->mips.begin(), r->mips.begin() + std::countr_zero(r->size / options.maxNormalMapSize));
        r->size = options.maxNormalMapSize;
      }
      return r;
    }();
    if (b) {
      const std::vector<uint8_t>& top = b->mips.front();
      bool opaque = true;
      for (size_t i = 3; i < top.size() && opaque; i += 4) opaque = top[i] == 255;
      formats[t] = chooseTextureFormat(options.encoding, key.slots, key.colorSpace, opaque);
    } else if (!droppable(b.error(), options)) {
      for (size_t seen = firstFailed.load(); t < seen && !firstFailed.compare_exchange_weak(seen, t);) {
      }
    }
    results[t].emplace(std::move(b));
  });
  for (size_t t = 0; t < count; ++t)
    if (!*results[t] && !droppable(results[t]->error(), options))
      return results[t]->error();  // every image up to the first failed one ran
  dropUndecodedTextures(scene, keys.value(), results, formats, report);
  const size_t kept = keys->size();
  // The classes must fit the shading pass's bindings: merge formats where the chosen ones would open too many.
  std::vector<TextureClassKey> classKeys;
  for (size_t t = 0; t < kept; ++t) classKeys.push_back({(*results[t])->size, (*keys)[t].colorSpace, formats[t]});
  fitTextureClassFormats(classKeys, MAX_TEXTURE_CLASSES);
  tbb::parallel_for(size_t{0}, kept, [&](size_t t) {
    compressBakedImage(&results[t]->value(), classKeys[t].format, options.quality);
    if (progress) {
      std::lock_guard<std::mutex> lock(progressMutex);
      progress(++done, kept, imageAt((*keys)[t].image).name);
    }
  });
  std::vector<BakedImage> baked;
  baked.reserve(kept);
  for (size_t t = 0; t < kept; ++t) {
    Result<BakedImage>& b = *results[t];
    const TextureKey& key = (*keys)[t];
    const ImportedImage& image = imageAt(key.image);
    if (report && !b->resizeNote.empty()) {
      report->notes.push_back(fmt::format("{}: image {} '{}': {}", quoteForMessage(imported.name), key.image,
                                          quoteForMessage(image.name), b->resizeNote));
    }
    const int32_t source = size_t(key.image) < imported.images.size() ? key.image : -1;  // (derived: no glTF image)
    scene->textures.push_back({image.name, source, key.colorSpace, 0, 0, b->originalWidth, b->originalHeight});
    baked.push_back(std::move(b.value()));
  }
  buildClasses(baked, scene);
  if (report) {
    report->texelBytes = 0;
    report->rgba8Bytes = 0;
    for (const TextureClass& c : scene->textureClasses) {
      report->texelBytes += c.texels.size();
      TextureClass rgba8 = {c.size, c.colorSpace, c.layers, c.mipCount, TextureFormat::Rgba8, {}};
      report->rgba8Bytes += rgba8.totalBytes();
    }
  }
  return {};
}

}  // namespace visbuf
