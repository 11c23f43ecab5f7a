// Mean linear colour of a texture image, used to turn a textured material into one Lambertian albedo (the
// bake works per triangle, not per texel). Images are decoded with stb_image (compiled here, with static
// linkage so it cannot clash with the copy inside libtinygltf/libstb); 8- and 16-bit channels are
// sRGB-decoded with the IEC 61966-2-1 curve before averaging, so a 50 % grey checkerboard of black and white
// averages to 0.5, not to srgbToLinear(0.5). Also resolves texture file names written on other systems
// (backslashes, case).
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <system_error>
#include <vector>

#include "loaders.h"

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#endif
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace tetraprobe::detail {

namespace {

// Decoding table for 8-bit sRGB.
const std::array<float, 256>& srgb8Table() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[static_cast<size_t>(i)] = srgbToLinear(static_cast<float>(i) / 255.0f);
    return t;
  }();
  return table;
}

// Averages the first three channels of `channels`-channel texels (grey images replicate channel 0).
template <typename T, typename Decode>
glm::vec3 meanOf(const T* data, size_t texels, int channels, Decode decode) {
  double sum[3] = {0.0, 0.0, 0.0};
  const bool grey = channels < 3;
  for (size_t i = 0; i < texels; ++i) {
    const T* px = data + i * static_cast<size_t>(channels);
    for (int c = 0; c < 3; ++c) sum[c] += decode(px[grey ? 0 : c]);
  }
  const double n = static_cast<double>(texels);
  return glm::vec3(static_cast<float>(sum[0] / n), static_cast<float>(sum[1] / n),
                   static_cast<float>(sum[2] / n));
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool isFile(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

// Walks `rel` one component at a time below `base`, accepting a directory entry whose name matches
// case-insensitively when the exact name is absent.
std::optional<std::filesystem::path> caseInsensitiveLookup(const std::filesystem::path& base,
                                                           const std::filesystem::path& rel) {
  std::filesystem::path cur = base;
  for (const auto& part : rel) {
    const std::string name = part.string();
    if (name.empty() || name == ".") continue;
    if (name == "..") {
      cur /= part;
      continue;
    }
    std::error_code ec;
    if (std::filesystem::exists(cur / part, ec)) {
      cur /= part;
      continue;
    }
    const std::string want = lower(name);
    bool found = false;
    std::filesystem::directory_iterator it(cur, ec), end;
    for (; !ec && it != end; it.increment(ec)) {
      if (lower(it->path().filename().string()) == want) {
        cur = it->path();
        found = true;
        break;
      }
    }
    if (!found) return std::nullopt;
  }
  if (isFile(cur)) return cur;
  return std::nullopt;
}

}  // namespace

float srgbToLinear(float encoded) {
  const float c = std::clamp(encoded, 0.0f, 1.0f);
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

std::optional<glm::vec3> meanLinearColor(const unsigned char* bytes, std::size_t size, std::string& error) {
  if (bytes == nullptr || size == 0) {
    error = "empty image data";
    return std::nullopt;
  }
  if (size > static_cast<std::size_t>(INT32_MAX)) {
    error = "image larger than 2 GiB";
    return std::nullopt;
  }
  const int len = static_cast<int>(size);
  int w = 0, h = 0, channels = 0;
  std::optional<glm::vec3> result;
  if (stbi_is_hdr_from_memory(bytes, len)) {
    float* data = stbi_loadf_from_memory(bytes, len, &w, &h, &channels, 0);
    if (data != nullptr && w > 0 && h > 0)
      result = meanOf(data, static_cast<size_t>(w) * static_cast<size_t>(h), channels,
                      [](float v) { return static_cast<double>(v); });
    stbi_image_free(data);
  } else if (stbi_is_16_bit_from_memory(bytes, len)) {
    stbi_us* data = stbi_load_16_from_memory(bytes, len, &w, &h, &channels, 0);
    if (data != nullptr && w > 0 && h > 0)
      result = meanOf(data, static_cast<size_t>(w) * static_cast<size_t>(h), channels, [](stbi_us v) {
        return static_cast<double>(srgbToLinear(static_cast<float>(v) / 65535.0f));
      });
    stbi_image_free(data);
  } else {
    stbi_uc* data = stbi_load_from_memory(bytes, len, &w, &h, &channels, 0);
    if (data != nullptr && w > 0 && h > 0) {
      const auto& table = srgb8Table();
      result = meanOf(data, static_cast<size_t>(w) * static_cast<size_t>(h), channels,
                      [&table](stbi_uc v) { return static_cast<double>(table[v]); });
    }
    stbi_image_free(data);
  }
  if (!result) {
    const char* reason = stbi_failure_reason();
    error = std::string("cannot decode image: ") + (reason ? reason : "unknown format");
  }
  return result;
}

std::optional<glm::vec3> meanLinearColorFile(const std::filesystem::path& file, std::string& error) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    error = "cannot open " + file.string();
    return std::nullopt;
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto mean = meanLinearColor(bytes.data(), bytes.size(), error);
  if (!mean) error = file.string() + ": " + error;
  return mean;
}

std::optional<AlphaTexture> decodeAlpha(const unsigned char* bytes, std::size_t size, AlphaSource source,
                                        std::string& error) {
  if (bytes == nullptr || size == 0) {
    error = "empty image data";
    return std::nullopt;
  }
  if (size > static_cast<std::size_t>(INT32_MAX)) {
    error = "image larger than 2 GiB";
    return std::nullopt;
  }
  const int len = static_cast<int>(size);
  int w = 0, h = 0, channels = 0;
  AlphaTexture out;
  // Which channel of a `channels`-channel texel to read, or -1 for "opaque".
  auto pick = [source](int channels) {
    const bool hasAlpha = channels == 2 || channels == 4;
    if (source == AlphaSource::kFirst) return 0;
    if (hasAlpha) return channels - 1;
    return source == AlphaSource::kAlphaElseFirst ? 0 : -1;
  };
  auto fill = [&](auto* data, auto toByte) {
    const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
    out.width = static_cast<uint32_t>(w);
    out.height = static_cast<uint32_t>(h);
    out.alpha.assign(n, 255);
    const int c = pick(channels);
    if (c < 0) return;
    for (size_t i = 0; i < n; ++i) out.alpha[i] = toByte(data[i * static_cast<size_t>(channels) + size_t(c)]);
  };
  bool ok = false;
  if (stbi_is_hdr_from_memory(bytes, len)) {
    float* data = stbi_loadf_from_memory(bytes, len, &w, &h, &channels, 0);
    if ((ok = data != nullptr && w > 0 && h > 0))
      fill(data,
           [](float v) { return static_cast<uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); });
    stbi_image_free(data);
  } else if (stbi_is_16_bit_from_memory(bytes, len)) {
    stbi_us* data = stbi_load_16_from_memory(bytes, len, &w, &h, &channels, 0);
    if ((ok = data != nullptr && w > 0 && h > 0))
      fill(data, [](stbi_us v) {
        return static_cast<uint8_t>((static_cast<unsigned>(v) * 255u + 32767u) / 65535u);
      });
    stbi_image_free(data);
  } else {
    stbi_uc* data = stbi_load_from_memory(bytes, len, &w, &h, &channels, 0);
    if ((ok = data != nullptr && w > 0 && h > 0))
      fill(data, [](stbi_uc v) { return static_cast<uint8_t>(v); });
    stbi_image_free(data);
  }
  if (!ok) {
    const char* reason = stbi_failure_reason();
    error = std::string("cannot decode image: ") + (reason ? reason : "unknown format");
    return std::nullopt;
  }
  return out;
}

std::optional<AlphaTexture> decodeAlphaFile(const std::filesystem::path& file, AlphaSource source,
                                            std::string& error) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    error = "cannot open " + file.string();
    return std::nullopt;
  }
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto texture = decodeAlpha(bytes.data(), bytes.size(), source, error);
  if (!texture)
    error = file.string() + ": " + error;
  else
    texture->name = file.filename().string();
  return texture;
}

float meanAlpha(const AlphaTexture& texture) {
  if (texture.alpha.empty()) return 1.0f;
  uint64_t sum = 0;
  for (uint8_t a : texture.alpha) sum += a;
  return static_cast<float>(static_cast<double>(sum) / (255.0 * static_cast<double>(texture.alpha.size())));
}

bool applyCutout(Scene& scene, Material& m, const AlphaTexture& texture, float cutoff, int32_t& slot) {
  bool holes = false, solid = false;
  for (uint8_t a : texture.alpha) {
    (static_cast<float>(a) * (1.0f / 255.0f) < cutoff ? holes : solid) = true;
    if (holes && solid) break;
  }
  if (!holes) return false;
  if (!solid) {
    m.transmission = 1.0f;
    return false;
  }
  if (slot < 0) {
    slot = static_cast<int32_t>(scene.alphaTextures.size());
    scene.alphaTextures.push_back(texture);
  }
  m.alphaTexture = slot;
  m.alphaCutoff = cutoff;
  return true;
}

std::optional<std::filesystem::path> resolveTexturePath(const std::filesystem::path& baseDir,
                                                        const std::string& name) {
  if (name.empty()) return std::nullopt;
  const std::filesystem::path given(name);
  const std::filesystem::path direct = given.is_absolute() ? given : baseDir / given;
  if (isFile(direct)) return direct;

  std::string slashed = name;
  std::replace(slashed.begin(), slashed.end(), '\\', '/');
  const std::filesystem::path rel(slashed);
  const std::filesystem::path joined = rel.is_absolute() ? rel : baseDir / rel;
  if (isFile(joined)) return joined;

  if (rel.is_absolute()) return caseInsensitiveLookup(rel.root_path(), rel.relative_path());
  return caseInsensitiveLookup(baseDir.empty() ? std::filesystem::path(".") : baseDir, rel);
}

}  // namespace tetraprobe::detail
