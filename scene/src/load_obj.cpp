// Wavefront OBJ + MTL loader. Parse: a line-numbered pre-scan of the OBJ checks what tinyobjloader would
// silently accept or skip (non-finite or missing vertex coordinates, face indices that are zero or out of
// range), then tinyobjloader reads and triangulates polygons. Materials: Kd (x the mean linear colour of
// map_Kd, as the MTL specification multiplies them) -> albedo; Ke (x the mean of map_Ke) -> emitted radiance
// in W/(m^2 sr) taken as is; d (or Tr, which tinyobjloader reads as 1 - d) -> transmission 1 - d; map_d ->
// a per-texel alpha cutout at 0.5 (with the faces' texture coordinates). A missing MTL or image is a warning.
// Texture means and alpha planes are computed once per file.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <tiny_obj_loader.h>

#include "loaders.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe::detail {

namespace {

// Pre-scan: throws InputError "<path>: line N: <problem>" for bad vertices and face indices. Returns the
// folders (relative to the OBJ) of the material libraries it names, where their textures may also live.
std::vector<std::filesystem::path> prescanObj(const std::string& path) {
  std::vector<std::filesystem::path> mtlDirs;
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  std::string line;
  size_t lineNo = 0;
  long long vertices = 0;
  long long maxIndex = 0;
  size_t maxIndexLine = 0;
  while (std::getline(in, line)) {
    ++lineNo;
    size_t i = line.find_first_not_of(" \t");
    if (i == std::string::npos || i + 1 >= line.size()) continue;
    if (line.compare(i, 7, "mtllib ") == 0) {
      std::istringstream names(line.substr(i + 7));
      std::string name;
      while (names >> name) {
        std::replace(name.begin(), name.end(), '\\', '/');
        const auto dir = std::filesystem::path(name).parent_path();
        if (!dir.empty() && std::find(mtlDirs.begin(), mtlDirs.end(), dir) == mtlDirs.end())
          mtlDirs.push_back(dir);
      }
      continue;
    }
    const char kind = line[i];
    if ((kind != 'v' && kind != 'f') || (line[i + 1] != ' ' && line[i + 1] != '\t')) continue;
    const char* p = line.c_str() + i + 2;
    if (kind == 'v') {
      for (int k = 0; k < 3; ++k) {
        char* end = nullptr;
        errno = 0;
        const double x = std::strtod(p, &end);
        if (end == p)
          throw InputError(path + ": line " + std::to_string(lineNo) + ": vertex needs 3 coordinates");
        if (!std::isfinite(x) || errno == ERANGE)
          throw InputError(path + ": line " + std::to_string(lineNo) + ": vertex coordinate is not finite");
        p = end;
      }
      ++vertices;
      continue;
    }
    std::istringstream tokens(p);
    std::string tok;
    while (tokens >> tok) {
      if (tok[0] == '#') break;
      char* end = nullptr;
      const long long idx = std::strtoll(tok.c_str(), &end, 10);
      if (end == tok.c_str())
        throw InputError(path + ": line " + std::to_string(lineNo) + ": malformed face index '" + tok + "'");
      if (idx == 0)
        throw InputError(path + ": line " + std::to_string(lineNo) + ": vertex index 0 is invalid");
      if (idx < 0 && vertices + idx < 0)
        throw InputError(path + ": line " + std::to_string(lineNo) + ": relative vertex index " +
                         std::to_string(idx) + " out of range (" + std::to_string(vertices) +
                         " vertices so far)");
      if (idx > maxIndex) {
        maxIndex = idx;
        maxIndexLine = lineNo;
      }
    }
  }
  if (maxIndex > vertices)
    throw InputError(path + ": line " + std::to_string(maxIndexLine) + ": vertex index " +
                     std::to_string(maxIndex) + " out of range (" + std::to_string(vertices) + " vertices)");
  return mtlDirs;
}

// Mean linear colour of a texture named in the MTL, cached per resolved file. nullopt (+ warning) on failure.
class TextureMeans {
 public:
  // Textures are looked up relative to `baseDir` (the OBJ's folder), then to each of `extraDirs` below it.
  TextureMeans(std::filesystem::path baseDir, std::vector<std::filesystem::path> extraDirs, Scene& scene)
      : baseDir_(std::move(baseDir)), extraDirs_(std::move(extraDirs)), scene_(scene) {}

  std::optional<glm::vec3> get(const std::string& name, const std::string& material) {
    auto it = byName_.find(name);
    if (it != byName_.end()) return it->second;
    std::optional<glm::vec3> mean;
    std::optional<std::filesystem::path> file = resolveTexturePath(baseDir_, name);
    for (size_t i = 0; !file && i < extraDirs_.size(); ++i)
      file = resolveTexturePath(baseDir_ / extraDirs_[i], name);
    if (file) {
      std::string error;
      mean = meanLinearColorFile(*file, error);
      if (!mean) scene_.warnings.push_back("material '" + material + "': texture " + error);
    } else {
      scene_.warnings.push_back("material '" + material + "': texture '" + name + "' not found under " +
                                baseDir_.string());
    }
    byName_.emplace(name, mean);
    return mean;
  }

 private:
  std::filesystem::path baseDir_;
  std::vector<std::filesystem::path> extraDirs_;
  Scene& scene_;
  std::map<std::string, std::optional<glm::vec3>> byName_;
};

// Alpha planes of map_d textures, decoded once per name; `slot` is the texture's index in
// Scene::alphaTextures once a material keeps it as a cutout.
class AlphaMaps {
 public:
  struct Entry {
    std::optional<AlphaTexture> texture;
    int32_t slot = -1;
  };

  AlphaMaps(std::filesystem::path baseDir, std::vector<std::filesystem::path> extraDirs, Scene& scene)
      : baseDir_(std::move(baseDir)), extraDirs_(std::move(extraDirs)), scene_(scene) {}

  Entry& get(const std::string& name, const std::string& material) {
    auto it = byName_.find(name);
    if (it != byName_.end()) return it->second;
    Entry e;
    std::optional<std::filesystem::path> file = resolveTexturePath(baseDir_, name);
    for (size_t i = 0; !file && i < extraDirs_.size(); ++i)
      file = resolveTexturePath(baseDir_ / extraDirs_[i], name);
    if (file) {
      std::string error;
      e.texture = decodeAlphaFile(*file, AlphaSource::kAlphaElseFirst, error);
      if (!e.texture)
        scene_.warnings.push_back("material '" + material + "': alpha texture (map_d) " + error +
                                  "; no cutout");
    } else {
      scene_.warnings.push_back("material '" + material + "': alpha texture (map_d) '" + name +
                                "' not found under " + baseDir_.string() + "; no cutout");
    }
    return byName_.emplace(name, std::move(e)).first->second;
  }

 private:
  std::filesystem::path baseDir_;
  std::vector<std::filesystem::path> extraDirs_;
  Scene& scene_;
  std::map<std::string, Entry> byName_;
};

TextureWrap wrapOf(const tinyobj::texture_option_t& opt) {
  return opt.clamp ? TextureWrap::kClampToEdge : TextureWrap::kRepeat;
}

void splitWarnings(const std::string& text, const std::string& path, Scene& scene) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line != ".") scene.warnings.push_back(path + ": " + line);
  }
}

}  // namespace

Scene loadObj(const std::string& path, const MeshOptions& options) {
  std::vector<std::filesystem::path> mtlDirs = prescanObj(path);

  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::string mtlDir = dir.string();
  if (!mtlDir.empty()) mtlDir += '/';

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> objMaterials;
  std::string warn, err;
  const bool ok = tinyobj::LoadObj(&attrib, &shapes, &objMaterials, &warn, &err, path.c_str(),
                                   mtlDir.empty() ? nullptr : mtlDir.c_str(), /*triangulate=*/true);
  Scene scene;
  splitWarnings(warn, path, scene);
  if (!ok) {
    std::string first = err.substr(0, err.find('\n'));
    throw InputError(path + ": " + (first.empty() ? "cannot parse OBJ" : first));
  }
  // tinyobjloader reports a missing or unreadable MTL in `err` but still succeeds.
  splitWarnings(err, path, scene);

  if (attrib.vertices.size() % 3 != 0) throw InputError(path + ": vertex array is not a multiple of 3");
  scene.positions.resize(attrib.vertices.size() / 3);
  for (size_t i = 0; i < scene.positions.size(); ++i)
    scene.positions[i] =
        glm::vec3(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]);

  TextureMeans textures(dir, mtlDirs, scene);
  AlphaMaps alphaMaps(dir, std::move(mtlDirs), scene);
  scene.materials.reserve(objMaterials.size() + 1);
  for (const tinyobj::material_t& m : objMaterials) {
    Material out;
    out.name = m.name;
    out.albedo = glm::vec3(m.diffuse[0], m.diffuse[1], m.diffuse[2]);
    out.emission = glm::vec3(m.emission[0], m.emission[1], m.emission[2]);
    if (options.textures && !m.diffuse_texname.empty()) {
      if (auto mean = textures.get(m.diffuse_texname, m.name)) out.albedo *= *mean;
    }
    if (options.textures && !m.emissive_texname.empty() && out.emission != glm::vec3(0.0f)) {
      if (auto mean = textures.get(m.emissive_texname, m.name)) out.emission *= *mean;
    }
    // tinyobjloader reads `d` as dissolve and `Tr` as 1 - dissolve (`d` wins when both are given).
    const float dissolve = static_cast<float>(m.dissolve);
    if (std::isfinite(dissolve)) out.transmission = std::clamp(1.0f - dissolve, 0.0f, 1.0f);
    if (!m.alpha_texname.empty() && out.transmission < 1.0f) {
      AlphaMaps::Entry& e = alphaMaps.get(m.alpha_texname, m.name);
      if (e.texture) {
        e.texture->wrapU = e.texture->wrapV = wrapOf(m.alpha_texopt);
        applyCutout(scene, out, *e.texture, 0.5f, e.slot);
      }
    }
    scene.materials.push_back(out);
  }
  const uint32_t materialCount = static_cast<uint32_t>(scene.materials.size());
  uint32_t defaultMaterial = UINT32_MAX;

  size_t total = 0;
  for (const auto& s : shapes) total += s.mesh.indices.size() / 3;
  scene.triangles.reserve(total);
  scene.triangleMaterial.reserve(total);
  const size_t nv = scene.positions.size();
  size_t cutoutWithoutUv = 0;
  for (const tinyobj::shape_t& shape : shapes) {
    const auto& idx = shape.mesh.indices;
    const size_t faces = idx.size() / 3;
    for (size_t f = 0; f < faces; ++f) {
      glm::uvec3 tri;
      for (int k = 0; k < 3; ++k) {
        const int v = idx[3 * f + static_cast<size_t>(k)].vertex_index;
        if (v < 0 || static_cast<size_t>(v) >= nv)
          throw InputError(path + ": shape '" + shape.name + "': vertex index " + std::to_string(v + 1) +
                           " out of range (" + std::to_string(nv) + " vertices)");
        tri[k] = static_cast<uint32_t>(v);
      }
      const int mid = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
      uint32_t material;
      if (mid >= 0 && static_cast<uint32_t>(mid) < materialCount) {
        material = static_cast<uint32_t>(mid);
      } else {
        if (defaultMaterial == UINT32_MAX) {
          defaultMaterial = static_cast<uint32_t>(scene.materials.size());
          scene.materials.push_back(Material{"default", glm::vec3(0.8f), glm::vec3(0.0f)});
        }
        material = defaultMaterial;
      }
      if (scene.materials[material].alphaTexture >= 0) {
        glm::vec2 uv[3];
        bool hasUv = true;
        const tinyobj::material_t& om = objMaterials[material];
        for (int k = 0; k < 3 && hasUv; ++k) {
          const int t = idx[3 * f + static_cast<size_t>(k)].texcoord_index;
          if (t < 0 || 2 * static_cast<size_t>(t) + 1 >= attrib.texcoords.size()) {
            hasUv = false;
            break;
          }
          // map_d -o / -s, then v flipped: OBJ's v runs up from the image's bottom row.
          const float u = attrib.texcoords[2 * static_cast<size_t>(t)] * om.alpha_texopt.scale[0] +
                          om.alpha_texopt.origin_offset[0];
          const float v = attrib.texcoords[2 * static_cast<size_t>(t) + 1] * om.alpha_texopt.scale[1] +
                          om.alpha_texopt.origin_offset[1];
          uv[k] = glm::vec2(u, 1.0f - v);
        }
        if (hasUv) {
          scene.cutoutTriangles.push_back(static_cast<uint32_t>(scene.triangles.size()));
          scene.cutoutUvs.insert(scene.cutoutUvs.end(), uv, uv + 3);
        } else {
          ++cutoutWithoutUv;
        }
      }
      scene.triangles.push_back(tri);
      scene.triangleMaterial.push_back(material);
    }
  }
  if (cutoutWithoutUv > 0)
    scene.warnings.push_back(path + ": " + std::to_string(cutoutWithoutUv) +
                             " face(s) with an alpha-textured (map_d) material have no texture coordinates; "
                             "they are not cut out");
  return scene;
}

}  // namespace tetraprobe::detail
