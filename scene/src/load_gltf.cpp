// glTF 2.0 loader (.gltf with external or data-URI buffers, .glb) on top of tinygltf. Parse with tinygltf
// (images kept encoded; only base-colour and emissive images are decoded, once each), then walk the node
// hierarchy of the default scene (else all root nodes) with cycle and depth guards, checking every accessor
// against its buffer before reading it. Triangles, strips and fans are read (indexed or not); points and
// lines are skipped with a warning; negative-determinant transforms flip the winding, as the spec requires.
// Materials: albedo = baseColorFactor x mean linear base-colour texture; emission = emissiveFactor x
// KHR_materials_emissive_strength x mean linear emissive texture. KHR_lights_punctual values are taken as
// radiometric (cd -> W/sr, lux -> W/m^2) and emissive nits as W/(m^2 sr), so an OBJ and a glTF export of
// the same level agree (docs/scene_format.md). Transparency: alphaMode BLEND -> transmission 1 - alpha (mean
// texture alpha), MASK -> a per-texel cutout of the base-colour texture's alpha (TEXCOORD_n with
// KHR_texture_transform, the sampler's wrap modes), KHR_materials_transmission -> transmission as well.
// Perspective cameras become named Camera entries.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <glm/trigonometric.hpp>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include <tiny_gltf.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include "loaders.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe::detail {

namespace {

constexpr int kMaxNodeDepth = 256;
constexpr size_t kMaxNodeVisits = 1u << 22;

// Image callback: keep the encoded bytes; decoding happens only for images a material uses.
bool keepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  image->as_is = true;
  if (size > 0) image->image.assign(bytes, bytes + size);
  return true;
}

// How a cutout material's triangles find their texture coordinates: TEXCOORD_<set>, then
// KHR_texture_transform's affine map (u' = m[0] u + m[1] v + m[2], v' = m[3] u + m[4] v + m[5]).
struct UvMapping {
  int set = 0;
  float m[6] = {1, 0, 0, 0, 1, 0};
};

// A decoded alpha plane and its slot in Scene::alphaTextures once a material keeps it as a cutout.
struct AlphaEntry {
  std::optional<AlphaTexture> texture;
  int32_t slot = -1;
};

struct Context {
  const tinygltf::Model& model;
  const std::string& path;
  Scene& scene;
  std::vector<uint32_t> materialMap;  // glTF material -> Scene material
  uint32_t defaultMaterial = UINT32_MAX;
  std::map<int, std::optional<glm::vec3>> imageMeans;
  std::vector<int> onPath;  // nodes on the current root-to-node path (cycle guard)
  size_t skippedPrimitives = 0;
  size_t visits = 0;  // node instances visited (guards against exponential DAG instancing)
  std::map<std::pair<int, int>, AlphaEntry> alphaPlanes;  // (texture, AlphaSource) -> plane
  std::map<uint32_t, UvMapping> cutoutUv;                 // Scene material with a cutout -> its UV mapping
  size_t cutoutWithoutUv = 0;                             // cutout primitives lacking texture coordinates
};

[[noreturn]] void fail(const Context& ctx, const std::string& what) {
  throw InputError(ctx.path + ": " + what);
}

// Byte span of accessor `index`, validated against its buffer view and buffer.
struct AccessorView {
  const unsigned char* data = nullptr;
  size_t count = 0;
  size_t stride = 0;
  int componentType = 0;
  int components = 0;
  bool normalized = false;
};

AccessorView viewAccessor(const Context& ctx, int index, const char* what) {
  const auto& m = ctx.model;
  if (index < 0 || static_cast<size_t>(index) >= m.accessors.size())
    fail(ctx, std::string(what) + " accessor " + std::to_string(index) + " out of range");
  const tinygltf::Accessor& a = m.accessors[static_cast<size_t>(index)];
  const std::string name = std::string(what) + " accessor " + std::to_string(index);
  const int compSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(a.componentType));
  const int comps = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(a.type));
  if (compSize <= 0 || comps <= 0) fail(ctx, name + ": bad component type or element type");
  if (a.sparse.isSparse) fail(ctx, name + ": sparse accessors are not supported");
  AccessorView v;
  v.count = a.count;
  v.componentType = a.componentType;
  v.components = comps;
  v.normalized = a.normalized;
  const size_t elemSize = static_cast<size_t>(compSize) * static_cast<size_t>(comps);
  if (a.count == 0) return v;
  if (a.bufferView < 0 || static_cast<size_t>(a.bufferView) >= m.bufferViews.size())
    fail(ctx, name + ": buffer view " + std::to_string(a.bufferView) + " out of range");
  const tinygltf::BufferView& bv = m.bufferViews[static_cast<size_t>(a.bufferView)];
  if (bv.buffer < 0 || static_cast<size_t>(bv.buffer) >= m.buffers.size())
    fail(ctx, name + ": buffer " + std::to_string(bv.buffer) + " out of range");
  const tinygltf::Buffer& buf = m.buffers[static_cast<size_t>(bv.buffer)];
  if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
    fail(ctx, name + ": buffer view exceeds its buffer (" + std::to_string(buf.data.size()) + " bytes)");
  v.stride = bv.byteStride != 0 ? bv.byteStride : elemSize;
  if (v.stride < elemSize) fail(ctx, name + ": byte stride smaller than an element");
  // Last byte read: byteOffset + stride * (count - 1) + elemSize, all within the view (overflow-safe).
  const size_t span = bv.byteLength;
  if (a.byteOffset > span || elemSize > span - a.byteOffset ||
      (a.count - 1) > (span - a.byteOffset - elemSize) / v.stride)
    fail(ctx, name + ": " + std::to_string(a.count) + " elements exceed buffer view of " +
                  std::to_string(span) + " bytes");
  v.data = buf.data.data() + bv.byteOffset + a.byteOffset;
  return v;
}

std::vector<glm::vec3> readPositions(const Context& ctx, int index) {
  const AccessorView v = viewAccessor(ctx, index, "POSITION");
  if (v.components != 3 || v.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT)
    fail(ctx, "POSITION accessor " + std::to_string(index) + " is not float VEC3");
  std::vector<glm::vec3> out(v.count);
  for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.data + i * v.stride, sizeof(float) * 3);
  return out;
}

std::vector<uint32_t> readIndices(const Context& ctx, int index) {
  const AccessorView v = viewAccessor(ctx, index, "index");
  if (v.components != 1) fail(ctx, "index accessor " + std::to_string(index) + " is not SCALAR");
  std::vector<uint32_t> out(v.count);
  for (size_t i = 0; i < v.count; ++i) {
    const unsigned char* p = v.data + i * v.stride;
    switch (v.componentType) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        out[i] = p[0];
        break;
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t x;
        std::memcpy(&x, p, 2);
        out[i] = x;
        break;
      }
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        std::memcpy(&out[i], p, 4);
        break;
      default:
        fail(ctx, "index accessor " + std::to_string(index) + " has a non-unsigned component type");
    }
  }
  return out;
}

glm::dmat4 localMatrix(const Context& ctx, const tinygltf::Node& n, int index) {
  if (!n.matrix.empty()) {
    if (n.matrix.size() != 16) fail(ctx, "node " + std::to_string(index) + ": matrix needs 16 numbers");
    return glm::make_mat4(n.matrix.data());  // glTF and GLM are both column-major
  }
  glm::dmat4 t(1.0), r(1.0), s(1.0);
  if (!n.translation.empty()) {
    if (n.translation.size() != 3)
      fail(ctx, "node " + std::to_string(index) + ": translation needs 3 numbers");
    t[3] = glm::dvec4(n.translation[0], n.translation[1], n.translation[2], 1.0);
  }
  if (!n.rotation.empty()) {
    if (n.rotation.size() != 4) fail(ctx, "node " + std::to_string(index) + ": rotation needs 4 numbers");
    glm::dquat q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);  // glTF stores x, y, z, w
    const double len = glm::length(q);
    if (!(len > 0.0)) fail(ctx, "node " + std::to_string(index) + ": zero rotation quaternion");
    r = glm::mat4_cast(q / len);
  }
  if (!n.scale.empty()) {
    if (n.scale.size() != 3) fail(ctx, "node " + std::to_string(index) + ": scale needs 3 numbers");
    s[0][0] = n.scale[0];
    s[1][1] = n.scale[1];
    s[2][2] = n.scale[2];
  }
  return t * r * s;
}

glm::vec3 rgb(const std::vector<double>& v, double fallback) {
  return glm::vec3(static_cast<float>(v.size() > 0 ? v[0] : fallback),
                   static_cast<float>(v.size() > 1 ? v[1] : fallback),
                   static_cast<float>(v.size() > 2 ? v[2] : fallback));
}

// Mean linear colour of texture `textureIndex`, nullopt (+ warning) when it cannot be had.
std::optional<glm::vec3> textureMean(Context& ctx, int textureIndex, const std::string& material) {
  const auto& m = ctx.model;
  if (textureIndex < 0 || static_cast<size_t>(textureIndex) >= m.textures.size()) {
    ctx.scene.warnings.push_back(ctx.path + ": material '" + material + "': texture " +
                                 std::to_string(textureIndex) + " out of range");
    return std::nullopt;
  }
  const int source = m.textures[static_cast<size_t>(textureIndex)].source;
  if (source < 0 || static_cast<size_t>(source) >= m.images.size()) {
    ctx.scene.warnings.push_back(ctx.path + ": material '" + material + "': texture without a usable image");
    return std::nullopt;
  }
  auto it = ctx.imageMeans.find(source);
  if (it != ctx.imageMeans.end()) return it->second;
  const tinygltf::Image& img = m.images[static_cast<size_t>(source)];
  std::optional<glm::vec3> mean;
  std::string error;
  if (!img.image.empty()) {
    mean = meanLinearColor(img.image.data(), img.image.size(), error);
  } else if (!img.uri.empty()) {
    // tinygltf could not read it as given; retry forgivingly (backslashes, case).
    const std::filesystem::path dir = std::filesystem::path(ctx.path).parent_path();
    if (auto file = resolveTexturePath(dir, img.uri)) {
      mean = meanLinearColorFile(*file, error);
    } else {
      error = "image '" + img.uri + "' not found";
    }
  } else {
    error = "image " + std::to_string(source) + " has no data";
  }
  if (!mean) ctx.scene.warnings.push_back(ctx.path + ": material '" + material + "': " + error);
  ctx.imageMeans.emplace(source, mean);
  return mean;
}

// The encoded bytes of texture `textureIndex`'s image, decoded into an alpha plane (cached per texture and
// source); wrap modes from its sampler. nullptr (+ warning) when it cannot be had.
AlphaEntry* textureAlpha(Context& ctx, int textureIndex, AlphaSource source, const std::string& material) {
  const auto key = std::make_pair(textureIndex, static_cast<int>(source));
  auto it = ctx.alphaPlanes.find(key);
  if (it != ctx.alphaPlanes.end()) return it->second.texture ? &it->second : nullptr;
  AlphaEntry& e = ctx.alphaPlanes[key];
  const auto& m = ctx.model;
  std::string error;
  if (textureIndex < 0 || static_cast<size_t>(textureIndex) >= m.textures.size()) {
    error = "texture " + std::to_string(textureIndex) + " out of range";
  } else {
    const tinygltf::Texture& tex = m.textures[static_cast<size_t>(textureIndex)];
    if (tex.source < 0 || static_cast<size_t>(tex.source) >= m.images.size()) {
      error = "texture without a usable image";
    } else {
      const tinygltf::Image& img = m.images[static_cast<size_t>(tex.source)];
      if (!img.image.empty()) {
        e.texture = decodeAlpha(img.image.data(), img.image.size(), source, error);
        if (e.texture) e.texture->name = img.uri.empty() ? "image " + std::to_string(tex.source) : img.uri;
      } else if (!img.uri.empty()) {
        const std::filesystem::path dir = std::filesystem::path(ctx.path).parent_path();
        if (auto file = resolveTexturePath(dir, img.uri))
          e.texture = decodeAlphaFile(*file, source, error);
        else
          error = "image '" + img.uri + "' not found";
      } else {
        error = "image " + std::to_string(tex.source) + " has no data";
      }
      if (e.texture && tex.sampler >= 0 && static_cast<size_t>(tex.sampler) < m.samplers.size()) {
        auto wrap = [](int mode) {
          return mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? TextureWrap::kClampToEdge
                 : mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? TextureWrap::kMirroredRepeat
                                                                 : TextureWrap::kRepeat;
        };
        e.texture->wrapU = wrap(m.samplers[static_cast<size_t>(tex.sampler)].wrapS);
        e.texture->wrapV = wrap(m.samplers[static_cast<size_t>(tex.sampler)].wrapT);
      }
    }
  }
  if (!e.texture) {
    ctx.scene.warnings.push_back(ctx.path + ": material '" + material + "': alpha: " + error +
                                 "; treated as opaque");
    return nullptr;
  }
  return &e;
}

double extensionNumber(const tinygltf::ExtensionMap& extensions, const char* extension, const char* key,
                       double fallback) {
  auto ext = extensions.find(extension);
  if (ext == extensions.end() || !ext->second.Has(key)) return fallback;
  const tinygltf::Value& v = ext->second.Get(key);
  return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
}

// TEXCOORD set and KHR_texture_transform of a texture reference.
UvMapping uvMapping(const tinygltf::TextureInfo& info) {
  UvMapping map;
  map.set = info.texCoord;
  auto ext = info.extensions.find("KHR_texture_transform");
  if (ext == info.extensions.end()) return map;
  const tinygltf::Value& t = ext->second;
  auto num = [&t](const char* key, int index, double fallback) {
    if (!t.Has(key)) return fallback;
    const tinygltf::Value& v = t.Get(key);
    if (index < 0) return v.IsNumber() ? v.GetNumberAsDouble() : fallback;
    if (!v.IsArray() || v.ArrayLen() <= static_cast<size_t>(index)) return fallback;
    const tinygltf::Value& x = v.Get(index);
    return x.IsNumber() ? x.GetNumberAsDouble() : fallback;
  };
  const double ox = num("offset", 0, 0.0), oy = num("offset", 1, 0.0), r = num("rotation", -1, 0.0);
  const double sx = num("scale", 0, 1.0), sy = num("scale", 1, 1.0);
  // Translation x Rotation x Scale as the extension defines them (rotation counter-clockwise in UV space).
  const double c = std::cos(r), s = std::sin(r);
  map.m[0] = static_cast<float>(c * sx);
  map.m[1] = static_cast<float>(s * sy);
  map.m[2] = static_cast<float>(ox);
  map.m[3] = static_cast<float>(-s * sx);
  map.m[4] = static_cast<float>(c * sy);
  map.m[5] = static_cast<float>(oy);
  if (t.Has("texCoord") && t.Get("texCoord").IsInt()) map.set = t.Get("texCoord").Get<int>();
  return map;
}

// alphaMode and KHR_materials_transmission -> transmission and cutout (docs/scene_format.md).
void convertTransparency(Context& ctx, const tinygltf::Material& gm, Material& out, uint32_t sceneIndex) {
  const auto& pbr = gm.pbrMetallicRoughness;
  const double factorAlpha = pbr.baseColorFactor.size() > 3 ? pbr.baseColorFactor[3] : 1.0;
  const float alpha =
      std::isfinite(factorAlpha) ? static_cast<float>(std::clamp(factorAlpha, 0.0, 1.0)) : 1.0f;
  const int texture = pbr.baseColorTexture.index;
  if (gm.alphaMode == "BLEND") {
    // Coverage: a fraction alpha of the surface is there; the rest lets light through.
    float a = alpha;
    if (texture >= 0) {
      if (AlphaEntry* e = textureAlpha(ctx, texture, AlphaSource::kAlphaElseOpaque, out.name))
        a *= meanAlpha(*e->texture);
    }
    out.transmission = 1.0f - a;
  } else if (gm.alphaMode == "MASK") {
    // Visible where alpha x texel alpha >= cutoff, i.e. texel alpha >= cutoff / alpha.
    const float cutoff = std::isfinite(gm.alphaCutoff) ? static_cast<float>(gm.alphaCutoff) : 0.5f;
    if (cutoff <= 0.0f) {
      // every texel passes: opaque
    } else if (alpha < cutoff && (texture < 0 || alpha <= 0.0f)) {
      out.transmission = 1.0f;  // nothing passes the cutoff: a hole everywhere
    } else if (texture >= 0) {
      if (AlphaEntry* e = textureAlpha(ctx, texture, AlphaSource::kAlphaElseOpaque, out.name)) {
        if (applyCutout(ctx.scene, out, *e->texture, cutoff / alpha, e->slot))
          ctx.cutoutUv[sceneIndex] = uvMapping(pbr.baseColorTexture);
      }
    }
  } else if (!gm.alphaMode.empty() && gm.alphaMode != "OPAQUE") {
    ctx.scene.warnings.push_back(ctx.path + ": material '" + out.name + "': unknown alphaMode '" +
                                 gm.alphaMode + "'; treated as opaque");
  }
  auto ext = gm.extensions.find("KHR_materials_transmission");
  if (ext != gm.extensions.end()) {
    double t = extensionNumber(gm.extensions, "KHR_materials_transmission", "transmissionFactor", 0.0);
    t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
    if (t > 0.0 && ext->second.Has("transmissionTexture")) {
      const tinygltf::Value& info = ext->second.Get("transmissionTexture");
      if (info.Has("index") && info.Get("index").IsInt()) {
        // The red channel, linear, multiplies the factor; its mean stands for the surface.
        if (AlphaEntry* e = textureAlpha(ctx, info.Get("index").Get<int>(), AlphaSource::kFirst, out.name))
          t *= meanAlpha(*e->texture);
      }
    }
    // Of the light the coverage lets meet the surface, a fraction t passes through as well.
    out.transmission = 1.0f - (1.0f - out.transmission) * (1.0f - static_cast<float>(t));
  }
}

void convertMaterials(Context& ctx, bool textures) {
  const auto& m = ctx.model;
  ctx.materialMap.resize(m.materials.size());
  for (size_t i = 0; i < m.materials.size(); ++i) {
    const tinygltf::Material& gm = m.materials[i];
    Material out;
    out.name = gm.name.empty() ? "material_" + std::to_string(i) : gm.name;
    const auto& pbr = gm.pbrMetallicRoughness;
    out.albedo = rgb(pbr.baseColorFactor, 1.0);
    if (textures && pbr.baseColorTexture.index >= 0) {
      if (auto mean = textureMean(ctx, pbr.baseColorTexture.index, out.name)) out.albedo *= *mean;
    }
    out.emission = rgb(gm.emissiveFactor, 0.0);
    auto ext = gm.extensions.find("KHR_materials_emissive_strength");
    if (ext != gm.extensions.end() && ext->second.Has("emissiveStrength")) {
      const tinygltf::Value& s = ext->second.Get("emissiveStrength");
      if (s.IsNumber()) out.emission *= static_cast<float>(s.GetNumberAsDouble());
    }
    if (textures && gm.emissiveTexture.index >= 0 && out.emission != glm::vec3(0.0f)) {
      if (auto mean = textureMean(ctx, gm.emissiveTexture.index, out.name)) out.emission *= *mean;
    }
    const uint32_t sceneIndex = static_cast<uint32_t>(ctx.scene.materials.size());
    convertTransparency(ctx, gm, out, sceneIndex);
    ctx.materialMap[i] = sceneIndex;
    ctx.scene.materials.push_back(out);
  }
}

uint32_t sceneMaterial(Context& ctx, int gltfMaterial) {
  if (gltfMaterial >= 0 && static_cast<size_t>(gltfMaterial) < ctx.materialMap.size())
    return ctx.materialMap[static_cast<size_t>(gltfMaterial)];
  if (gltfMaterial >= 0)
    ctx.scene.warnings.push_back(ctx.path + ": material " + std::to_string(gltfMaterial) +
                                 " out of range; using default");
  if (ctx.defaultMaterial == UINT32_MAX) {
    ctx.defaultMaterial = static_cast<uint32_t>(ctx.scene.materials.size());
    ctx.scene.materials.push_back(Material{"default", glm::vec3(0.8f), glm::vec3(0.0f)});
  }
  return ctx.defaultMaterial;
}

// TEXCOORD_<map.set> of a primitive with `vertices` vertices, mapped by `map`: float, or normalised unsigned
// byte / short, VEC2. Empty when the primitive has none or they do not fit (the caller warns).
std::vector<glm::vec2> readTexcoords(const Context& ctx, const tinygltf::Primitive& prim,
                                     const UvMapping& map, size_t vertices) {
  auto it = prim.attributes.find("TEXCOORD_" + std::to_string(map.set));
  if (it == prim.attributes.end()) return {};
  const AccessorView v = viewAccessor(ctx, it->second, "TEXCOORD");
  if (v.components != 2 || v.count != vertices) return {};
  std::vector<glm::vec2> out(v.count);
  for (size_t i = 0; i < v.count; ++i) {
    const unsigned char* p = v.data + i * v.stride;
    glm::vec2 uv;
    if (v.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
      std::memcpy(&uv, p, sizeof(float) * 2);
    } else if (v.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && v.normalized) {
      uv = glm::vec2(p[0], p[1]) / 255.0f;
    } else if (v.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT && v.normalized) {
      uint16_t x[2];
      std::memcpy(x, p, 4);
      uv = glm::vec2(x[0], x[1]) / 65535.0f;
    } else {
      return {};
    }
    out[i] =
        glm::vec2(map.m[0] * uv.x + map.m[1] * uv.y + map.m[2], map.m[3] * uv.x + map.m[4] * uv.y + map.m[5]);
  }
  return out;
}

void addPrimitive(Context& ctx, const tinygltf::Primitive& prim, const glm::dmat4& world, size_t meshIndex) {
  const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
  if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
      mode != TINYGLTF_MODE_TRIANGLE_FAN) {
    ++ctx.skippedPrimitives;
    return;
  }
  auto pos = prim.attributes.find("POSITION");
  if (pos == prim.attributes.end()) {
    ctx.scene.warnings.push_back(ctx.path + ": mesh " + std::to_string(meshIndex) +
                                 ": primitive without POSITION skipped");
    return;
  }
  const std::vector<glm::vec3> local = readPositions(ctx, pos->second);
  std::vector<uint32_t> indices;
  if (prim.indices >= 0) {
    indices = readIndices(ctx, prim.indices);
    for (uint32_t i : indices) {
      if (i >= local.size())
        fail(ctx, "mesh " + std::to_string(meshIndex) + ": vertex index " + std::to_string(i) +
                      " out of range (" + std::to_string(local.size()) + " vertices)");
    }
  } else {
    indices.resize(local.size());
    for (size_t i = 0; i < local.size(); ++i) indices[i] = static_cast<uint32_t>(i);
  }

  const uint32_t base = static_cast<uint32_t>(ctx.scene.positions.size());
  if (ctx.scene.positions.size() + local.size() > UINT32_MAX) fail(ctx, "more than 2^32 vertices");
  for (const glm::vec3& p : local) {
    const glm::dvec4 w = world * glm::dvec4(glm::dvec3(p), 1.0);
    ctx.scene.positions.emplace_back(static_cast<float>(w.x), static_cast<float>(w.y),
                                     static_cast<float>(w.z));
  }
  const bool flip = glm::determinant(glm::dmat3(world)) < 0.0;
  const uint32_t material = sceneMaterial(ctx, prim.material);
  std::vector<glm::vec2> uvs;  // per vertex, only for a cutout material
  if (ctx.scene.materials[material].alphaTexture >= 0) {
    const UvMapping& map = ctx.cutoutUv[material];
    uvs = readTexcoords(ctx, prim, map, local.size());
    if (uvs.empty()) ++ctx.cutoutWithoutUv;
  }
  auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
    if (flip) std::swap(b, c);
    if (!uvs.empty()) {
      ctx.scene.cutoutTriangles.push_back(static_cast<uint32_t>(ctx.scene.triangles.size()));
      ctx.scene.cutoutUvs.insert(ctx.scene.cutoutUvs.end(), {uvs[a], uvs[b], uvs[c]});
    }
    ctx.scene.triangles.emplace_back(base + a, base + b, base + c);
    ctx.scene.triangleMaterial.push_back(material);
  };
  const size_t n = indices.size();
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (n % 3 != 0)
      ctx.scene.warnings.push_back(ctx.path + ": mesh " + std::to_string(meshIndex) +
                                   ": index count not a multiple of 3; trailing indices ignored");
    for (size_t i = 0; i + 2 < n; i += 3) emit(indices[i], indices[i + 1], indices[i + 2]);
  } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
    for (size_t i = 0; i + 2 < n; ++i) {
      if (i % 2 == 0)
        emit(indices[i], indices[i + 1], indices[i + 2]);
      else
        emit(indices[i + 1], indices[i], indices[i + 2]);
    }
  } else {
    for (size_t i = 1; i + 1 < n; ++i) emit(indices[0], indices[i], indices[i + 1]);
  }
}

void addLight(Context& ctx, const tinygltf::Node& node, const glm::dmat4& world) {
  auto ext = node.extensions.find("KHR_lights_punctual");
  if (ext == node.extensions.end() || !ext->second.Has("light")) return;
  const tinygltf::Value& li = ext->second.Get("light");
  if (!li.IsInt() || li.Get<int>() < 0 || static_cast<size_t>(li.Get<int>()) >= ctx.model.lights.size())
    fail(ctx, "node '" + node.name + "': KHR_lights_punctual light index out of range");
  const tinygltf::Light& gl = ctx.model.lights[static_cast<size_t>(li.Get<int>())];
  Light out;
  out.intensity = rgb(gl.color, 1.0) * static_cast<float>(gl.intensity);
  const glm::dvec4 p = world * glm::dvec4(0, 0, 0, 1);
  out.position = glm::vec3(p);
  const glm::dvec3 d = glm::dmat3(world) * glm::dvec3(0, 0, -1);
  const double len = glm::length(d);
  out.direction = len > 0.0 ? glm::vec3(d / len) : glm::vec3(0, 0, -1);
  if (gl.type == "point") {
    out.type = LightType::kPoint;
  } else if (gl.type == "spot") {
    out.type = LightType::kSpot;
    out.innerConeRad = static_cast<float>(gl.spot.innerConeAngle);
    out.outerConeRad = static_cast<float>(gl.spot.outerConeAngle);
  } else if (gl.type == "directional") {
    out.type = LightType::kDirectional;
  } else {
    ctx.scene.warnings.push_back(ctx.path + ": light '" + gl.name + "' has unknown type '" + gl.type +
                                 "'; skipped");
    return;
  }
  ctx.scene.lights.push_back(out);
}

void addCamera(Context& ctx, const tinygltf::Node& node, const glm::dmat4& world) {
  if (node.camera < 0) return;
  if (static_cast<size_t>(node.camera) >= ctx.model.cameras.size())
    fail(ctx, "node '" + node.name + "': camera " + std::to_string(node.camera) + " out of range");
  const tinygltf::Camera& gc = ctx.model.cameras[static_cast<size_t>(node.camera)];
  if (gc.type != "perspective") {
    ctx.scene.warnings.push_back(ctx.path + ": camera '" + gc.name + "' is not perspective; skipped");
    return;
  }
  Camera out;
  out.name = !gc.name.empty()     ? gc.name
             : !node.name.empty() ? node.name
                                  : "camera_" + std::to_string(node.camera);
  out.eye = glm::vec3(world * glm::dvec4(0, 0, 0, 1));
  const glm::dvec3 fwd = glm::dmat3(world) * glm::dvec3(0, 0, -1);
  const glm::dvec3 up = glm::dmat3(world) * glm::dvec3(0, 1, 0);
  if (glm::length(fwd) > 0.0) out.target = out.eye + glm::vec3(glm::normalize(fwd));
  if (glm::length(up) > 0.0) out.up = glm::vec3(glm::normalize(up));
  if (gc.perspective.yfov > 0.0) out.fovYDeg = static_cast<float>(glm::degrees(gc.perspective.yfov));
  ctx.scene.cameras.push_back(out);
}

void visitNode(Context& ctx, int index, const glm::dmat4& parent) {
  const auto& m = ctx.model;
  if (index < 0 || static_cast<size_t>(index) >= m.nodes.size())
    fail(ctx, "node " + std::to_string(index) + " out of range");
  for (int n : ctx.onPath) {
    if (n == index)
      fail(ctx, "node " + std::to_string(index) + " is its own ancestor (cycle in the node tree)");
  }
  if (ctx.onPath.size() >= static_cast<size_t>(kMaxNodeDepth)) fail(ctx, "node tree deeper than 256 levels");
  if (++ctx.visits > kMaxNodeVisits) fail(ctx, "node tree instances more than 4M nodes");
  const tinygltf::Node& node = m.nodes[static_cast<size_t>(index)];
  const glm::dmat4 world = parent * localMatrix(ctx, node, index);
  if (node.mesh >= 0) {
    if (static_cast<size_t>(node.mesh) >= m.meshes.size())
      fail(ctx, "node " + std::to_string(index) + ": mesh " + std::to_string(node.mesh) + " out of range");
    for (const auto& prim : m.meshes[static_cast<size_t>(node.mesh)].primitives)
      addPrimitive(ctx, prim, world, static_cast<size_t>(node.mesh));
  }
  addLight(ctx, node, world);
  addCamera(ctx, node, world);
  ctx.onPath.push_back(index);
  for (int child : node.children) visitNode(ctx, child, world);
  ctx.onPath.pop_back();
}

}  // namespace

Scene loadGltf(const std::string& path, const MeshOptions& options) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keepEncodedImage, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = path.size() >= 4 && (path.compare(path.size() - 4, 4, ".glb") == 0 ||
                                           path.compare(path.size() - 4, 4, ".GLB") == 0);
  const bool ok = binary ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                         : loader.LoadASCIIFromFile(&model, &err, &warn, path);
  if (!ok) {
    std::string first = err.substr(0, err.find('\n'));
    while (!first.empty() && (first.back() == '\r' || first.back() == ' ')) first.pop_back();
    throw InputError(path + ": " + (first.empty() ? "cannot parse glTF" : first));
  }
  Scene scene;
  {
    std::string line;
    for (char c : warn) {
      if (c == '\n') {
        if (!line.empty()) scene.warnings.push_back(path + ": " + line);
        line.clear();
      } else {
        line += c;
      }
    }
    if (!line.empty()) scene.warnings.push_back(path + ": " + line);
  }

  Context ctx{model, path, scene};
  for (const std::string& ext : model.extensionsRequired) {
    if (ext != "KHR_lights_punctual" && ext != "KHR_materials_emissive_strength" &&
        ext != "KHR_texture_transform" && ext != "KHR_materials_pbrSpecularGlossiness" &&
        ext != "KHR_materials_unlit" && ext != "KHR_materials_transmission")
      throw InputError(path + ": requires unsupported glTF extension " + ext);
  }
  convertMaterials(ctx, options.textures);

  std::vector<int> roots;
  int sceneIndex = model.defaultScene;
  if (sceneIndex < 0 && !model.scenes.empty()) sceneIndex = 0;
  if (sceneIndex >= 0 && static_cast<size_t>(sceneIndex) < model.scenes.size()) {
    roots = model.scenes[static_cast<size_t>(sceneIndex)].nodes;
  } else {
    std::vector<bool> isChild(model.nodes.size(), false);
    for (const auto& n : model.nodes) {
      for (int c : n.children) {
        if (c >= 0 && static_cast<size_t>(c) < isChild.size()) isChild[static_cast<size_t>(c)] = true;
      }
    }
    for (size_t i = 0; i < model.nodes.size(); ++i) {
      if (!isChild[i]) roots.push_back(static_cast<int>(i));
    }
  }
  for (int r : roots) visitNode(ctx, r, glm::dmat4(1.0));
  if (ctx.cutoutWithoutUv > 0)
    scene.warnings.push_back(
        path + ": " + std::to_string(ctx.cutoutWithoutUv) +
        " primitive(s) with an alphaMode MASK texture have no usable texture coordinates; "
        "they are not cut out");
  if (ctx.skippedPrimitives > 0)
    scene.warnings.push_back(path + ": skipped " + std::to_string(ctx.skippedPrimitives) +
                             " point/line primitive" + (ctx.skippedPrimitives == 1 ? "" : "s"));
  return scene;
}

}  // namespace tetraprobe::detail
