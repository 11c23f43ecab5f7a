// loadScene(): picks the loader by file extension (.obj, .gltf/.glb, .scene.json), then runs the validation
// every loader shares (finite positions, indices and material ids in range, at least one triangle, zero-area
// triangles dropped with a warning). Loaders parse, this file validates; both report bad input as InputError
// "<file>: <problem>" and never abort the process.
#include "tetraprobe/scene/load.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <string>

#include <glm/geometric.hpp>

#include "loaders.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe {

namespace detail {

namespace {

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string vecString(const glm::vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", static_cast<double>(v.x), static_cast<double>(v.y),
                static_cast<double>(v.z));
  return buf;
}

}  // namespace

void validateScene(Scene& scene, const std::string& path) {
  const size_t nv = scene.positions.size();
  for (size_t i = 0; i < nv; ++i) {
    if (!finite(scene.positions[i]))
      throw InputError(path + ": vertex " + std::to_string(i) + " has a non-finite coordinate " +
                       vecString(scene.positions[i]));
  }
  if (scene.triangleMaterial.size() != scene.triangles.size())
    throw InputError(path + ": internal: " + std::to_string(scene.triangleMaterial.size()) +
                     " material ids for " + std::to_string(scene.triangles.size()) + " triangles");
  for (const Light& l : scene.lights) {
    if (!finite(l.position) || !finite(l.direction) || !finite(l.intensity))
      throw InputError(path + ": a light has a non-finite position, direction or intensity");
  }
  for (const Camera& c : scene.cameras) {
    if (!finite(c.eye) || !finite(c.target) || !finite(c.up) || !std::isfinite(c.fovYDeg))
      throw InputError(path + ": camera '" + c.name + "' has a non-finite value");
  }

  // Checked before triangles are dropped (the remapping below relies on it).
  if (const std::string problem = transparencyProblem(scene); !problem.empty())
    throw InputError(path + ": " + problem);
  size_t kept = 0;
  size_t degenerate = 0;
  size_t nextCutout = 0, keptCutouts = 0;  // cutoutTriangles follow the triangles they name
  for (size_t t = 0; t < scene.triangles.size(); ++t) {
    const glm::uvec3 tri = scene.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] >= nv)
        throw InputError(path + ": triangle " + std::to_string(t) + ": vertex index " +
                         std::to_string(tri[k]) + " out of range (" + std::to_string(nv) + " vertices)");
    }
    if (scene.triangleMaterial[t] >= scene.materials.size())
      throw InputError(path + ": triangle " + std::to_string(t) + ": material " +
                       std::to_string(scene.triangleMaterial[t]) + " out of range (" +
                       std::to_string(scene.materials.size()) + " materials)");
    const glm::vec3 a = scene.positions[tri.x], b = scene.positions[tri.y], c = scene.positions[tri.z];
    const glm::vec3 n = glm::cross(b - a, c - a);
    const float area2 = glm::dot(n, n);
    const bool listed = nextCutout < scene.cutoutTriangles.size() && scene.cutoutTriangles[nextCutout] == t;
    if (listed) ++nextCutout;
    if (!(area2 > 0.0f) || !std::isfinite(area2)) {
      ++degenerate;
      continue;
    }
    if (listed) {
      scene.cutoutTriangles[keptCutouts] = static_cast<uint32_t>(kept);
      for (size_t k = 0; k < 3; ++k)
        scene.cutoutUvs[3 * keptCutouts + k] = scene.cutoutUvs[3 * (nextCutout - 1) + k];
      ++keptCutouts;
    }
    scene.triangles[kept] = tri;
    scene.triangleMaterial[kept] = scene.triangleMaterial[t];
    ++kept;
  }
  scene.cutoutTriangles.resize(keptCutouts);
  scene.cutoutUvs.resize(3 * keptCutouts);
  scene.triangles.resize(kept);
  scene.triangleMaterial.resize(kept);
  if (degenerate > 0)
    scene.warnings.push_back(path + ": dropped " + std::to_string(degenerate) + " zero-area triangle" +
                             (degenerate == 1 ? "" : "s"));
  if (kept == 0) throw InputError(path + ": no triangles");
  for (const Material& m : scene.materials) {
    if (!finite(m.albedo) || !finite(m.emission))
      throw InputError(path + ": material '" + m.name + "' has a non-finite albedo or emission");
  }
}

}  // namespace detail

namespace {

std::string lowerCase(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Runs `load` turning any non-InputError exception into an InputError naming `path`, then validates.
template <typename Load>
Scene loadChecked(const std::string& path, Load load) {
  Scene scene;
  try {
    scene = load();
  } catch (const InputError&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw InputError(path + ": out of memory while loading (file too large or corrupt)");
  } catch (const std::exception& e) {
    throw InputError(path + ": " + e.what());
  }
  scene.sourcePath = path;
  detail::validateScene(scene, path);
  return scene;
}

void requireFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path + ": no such file");
}

}  // namespace

namespace detail {

Scene loadMesh(const std::string& path, const MeshOptions& options) {
  requireFile(path);
  const std::string name = lowerCase(path);
  if (endsWith(name, ".obj")) return loadChecked(path, [&] { return loadObj(path, options); });
  if (endsWith(name, ".gltf") || endsWith(name, ".glb"))
    return loadChecked(path, [&] { return loadGltf(path, options); });
  throw InputError(path + ": unknown mesh format (expected .obj, .gltf or .glb)");
}

}  // namespace detail

Scene loadScene(const std::string& path) {
  requireFile(path);
  if (endsWith(lowerCase(path), ".scene.json"))
    return loadChecked(path, [&] { return detail::loadSceneJson(path); });
  const std::string name = lowerCase(path);
  if (!endsWith(name, ".obj") && !endsWith(name, ".gltf") && !endsWith(name, ".glb"))
    throw InputError(path + ": unknown scene format (expected .obj, .gltf, .glb or .scene.json)");
  return detail::loadMesh(path, detail::MeshOptions{});
}

}  // namespace tetraprobe
