// Scene JSON loader (*.scene.json, schema in docs/scene_format.md): names a mesh file (OBJ or glTF, relative
// to the JSON), a unit scale, extra lights, sky, cameras, fine volumes and material overrides. Parse with
// nlohmann::json, then read each key with a typed accessor that throws InputError naming the key path
// ("lights[1].position: expected an array of 3 numbers"); unknown keys become warnings so that typos are
// seen.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <nlohmann/json.hpp>

#include "loaders.h"
#include "tetraprobe/common/error.h"

namespace tetraprobe::detail {

namespace {

using nlohmann::json;

struct Reader {
  const std::string& path;
  Scene& scene;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw InputError(path + ": " + key + ": " + what);
  }

  // Warns about keys of `obj` not in `known`.
  void checkKeys(const json& obj, const std::string& key, std::initializer_list<const char*> known) const {
    std::set<std::string> names;
    for (const char* k : known) names.insert(k);
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      if (!names.count(it.key()))
        scene.warnings.push_back(path + ": unknown key '" + (key.empty() ? "" : key + ".") + it.key() +
                                 "' ignored");
    }
  }

  const json& object(const json& j, const std::string& key) const {
    if (!j.is_object()) fail(key, "expected an object");
    return j;
  }
  const json& array(const json& j, const std::string& key) const {
    if (!j.is_array()) fail(key, "expected an array");
    return j;
  }
  float number(const json& j, const std::string& key) const {
    if (!j.is_number()) fail(key, "expected a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) fail(key, "expected a finite number");
    return static_cast<float>(v);
  }
  std::string string(const json& j, const std::string& key) const {
    if (!j.is_string()) fail(key, "expected a string");
    return j.get<std::string>();
  }
  glm::vec3 vec3(const json& j, const std::string& key) const {
    if (!j.is_array() || j.size() != 3) fail(key, "expected an array of 3 numbers");
    glm::vec3 v;
    for (int i = 0; i < 3; ++i) v[i] = number(j[static_cast<size_t>(i)], key + "[" + std::to_string(i) + "]");
    return v;
  }
  // An RGB colour: [r, g, b] or one number for grey. Must be >= 0.
  glm::vec3 colour(const json& j, const std::string& key) const {
    const glm::vec3 c = j.is_number() ? glm::vec3(number(j, key)) : vec3(j, key);
    if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) fail(key, "colour components must be >= 0");
    return c;
  }
  glm::vec3 direction(const json& j, const std::string& key) const {
    const glm::vec3 d = vec3(j, key);
    const float len = glm::length(d);
    if (!(len > 0.0f)) fail(key, "direction must not be zero");
    return d / len;
  }
};

void readLight(const Reader& r, const json& j, const std::string& key, float scale) {
  r.object(j, key);
  if (!j.contains("type")) r.fail(key + ".type", "missing (point, spot or directional)");
  const std::string type = r.string(j["type"], key + ".type");
  Light l;
  if (type == "point") {
    l.type = LightType::kPoint;
    r.checkKeys(j, key, {"type", "name", "position", "intensity", "radius"});
  } else if (type == "spot") {
    l.type = LightType::kSpot;
    r.checkKeys(
        j, key,
        {"type", "name", "position", "direction", "intensity", "radius", "inner_cone_deg", "outer_cone_deg"});
  } else if (type == "directional" || type == "sun") {
    l.type = LightType::kDirectional;
    r.checkKeys(j, key, {"type", "name", "direction", "irradiance", "angular_radius_deg"});
  } else {
    r.fail(key + ".type", "unknown light type '" + type + "' (point, spot or directional)");
  }
  if (j.contains("name")) r.string(j["name"], key + ".name");
  if (l.type != LightType::kDirectional) {
    if (!j.contains("position")) r.fail(key + ".position", "missing");
    if (!j.contains("intensity")) r.fail(key + ".intensity", "missing (W/sr)");
    l.position = r.vec3(j["position"], key + ".position") * scale;
    l.intensity = r.colour(j["intensity"], key + ".intensity");
    if (j.contains("radius")) {
      l.radius = r.number(j["radius"], key + ".radius") * scale;
      if (l.radius < 0.0f) r.fail(key + ".radius", "must be >= 0");
    }
  }
  if (l.type == LightType::kSpot) {
    if (!j.contains("direction")) r.fail(key + ".direction", "missing");
    l.direction = r.direction(j["direction"], key + ".direction");
    const float inner =
        j.contains("inner_cone_deg") ? r.number(j["inner_cone_deg"], key + ".inner_cone_deg") : 0.0f;
    const float outer =
        j.contains("outer_cone_deg") ? r.number(j["outer_cone_deg"], key + ".outer_cone_deg") : 45.0f;
    if (!(inner >= 0.0f && inner <= outer && outer > 0.0f && outer <= 90.0f))
      r.fail(key, "need 0 <= inner_cone_deg <= outer_cone_deg <= 90 and outer_cone_deg > 0");
    l.innerConeRad = glm::radians(inner);
    l.outerConeRad = glm::radians(outer);
  }
  if (l.type == LightType::kDirectional) {
    if (!j.contains("direction")) r.fail(key + ".direction", "missing (the direction light travels)");
    if (!j.contains("irradiance")) r.fail(key + ".irradiance", "missing (W/m^2)");
    l.direction = r.direction(j["direction"], key + ".direction");
    l.intensity = r.colour(j["irradiance"], key + ".irradiance");
    if (j.contains("angular_radius_deg")) {
      const float a = r.number(j["angular_radius_deg"], key + ".angular_radius_deg");
      if (a < 0.0f || a >= 90.0f) r.fail(key + ".angular_radius_deg", "must be in [0, 90)");
      l.angularRadiusRad = glm::radians(a);
    }
  }
  r.scene.lights.push_back(l);
}

void readCamera(const Reader& r, const json& j, const std::string& key, float scale) {
  r.object(j, key);
  r.checkKeys(j, key, {"name", "eye", "target", "up", "fov_deg"});
  Camera c;
  if (!j.contains("name")) r.fail(key + ".name", "missing");
  c.name = r.string(j["name"], key + ".name");
  if (!j.contains("eye")) r.fail(key + ".eye", "missing");
  if (!j.contains("target")) r.fail(key + ".target", "missing");
  c.eye = r.vec3(j["eye"], key + ".eye") * scale;
  c.target = r.vec3(j["target"], key + ".target") * scale;
  if (j.contains("up")) c.up = r.direction(j["up"], key + ".up");
  if (j.contains("fov_deg")) {
    c.fovYDeg = r.number(j["fov_deg"], key + ".fov_deg");
    if (!(c.fovYDeg > 0.0f && c.fovYDeg < 180.0f)) r.fail(key + ".fov_deg", "must be in (0, 180)");
  }
  if (c.eye == c.target) r.fail(key, "eye and target coincide");
  r.scene.cameras.push_back(c);
}

void readVolume(const Reader& r, const json& j, const std::string& key, float scale) {
  r.object(j, key);
  r.checkKeys(j, key, {"name", "min", "max"});
  Volume v;
  if (j.contains("name")) v.name = r.string(j["name"], key + ".name");
  if (!j.contains("min")) r.fail(key + ".min", "missing");
  if (!j.contains("max")) r.fail(key + ".max", "missing");
  v.min = r.vec3(j["min"], key + ".min") * scale;
  v.max = r.vec3(j["max"], key + ".max") * scale;
  if (!(v.min.x <= v.max.x && v.min.y <= v.max.y && v.min.z <= v.max.z)) r.fail(key, "min must be <= max");
  r.scene.fineVolumes.push_back(v);
}

void readMaterialOverride(const Reader& r, const std::string& name, const json& j, const std::string& key) {
  r.object(j, key);
  r.checkKeys(j, key, {"albedo", "emission", "emission_scale", "transmission"});
  bool found = false;
  for (Material& m : r.scene.materials) {
    if (m.name != name) continue;
    found = true;
    if (j.contains("albedo")) {
      m.albedo = r.colour(j["albedo"], key + ".albedo");
      if (m.albedo.x > 1.0f || m.albedo.y > 1.0f || m.albedo.z > 1.0f)
        r.fail(key + ".albedo", "components must be in [0, 1]");
    }
    if (j.contains("emission")) m.emission = r.colour(j["emission"], key + ".emission");
    if (j.contains("emission_scale")) {
      const float s = r.number(j["emission_scale"], key + ".emission_scale");
      if (s < 0.0f) r.fail(key + ".emission_scale", "must be >= 0");
      m.emission *= s;
    }
    if (j.contains("transmission")) {
      const float t = r.number(j["transmission"], key + ".transmission");
      if (!(t >= 0.0f && t <= 1.0f)) r.fail(key + ".transmission", "must be in [0, 1]");
      m.transmission = t;
    }
  }
  if (!found)
    r.scene.warnings.push_back(r.path + ": " + key + ": no material named '" + name + "' in the mesh");
}

}  // namespace

Scene loadSceneJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open file");
  json root;
  try {
    root = json::parse(in);
  } catch (const json::parse_error& e) {
    std::string what = e.what();
    // "[json.exception.parse_error.101] parse error at line 3, column 5: ..." -> drop the bracketed id
    const size_t close = what.find("] ");
    if (close != std::string::npos) what = what.substr(close + 2);
    throw InputError(path + ": malformed JSON: " + what);
  }
  Scene dummy;
  Reader pre{path, dummy};
  pre.object(root, "(top level)");
  if (!root.contains("mesh")) throw InputError(path + ": mesh: missing (path of an .obj/.gltf/.glb file)");
  const std::string meshName = pre.string(root["mesh"], "mesh");
  std::filesystem::path meshPath(meshName);
  if (meshPath.is_relative()) meshPath = std::filesystem::path(path).parent_path() / meshPath;
  const std::string meshFile = meshPath.string();

  MeshOptions options;
  if (root.contains("textures")) {
    const std::string mode = pre.string(root["textures"], "textures");
    if (mode == "ignore") {
      options.textures = false;
    } else if (mode != "multiply") {
      throw InputError(path + ": textures: expected \"multiply\" or \"ignore\", got \"" + mode + "\"");
    }
  }

  float scale = 1.0f;
  if (root.contains("unit_scale")) {
    scale = pre.number(root["unit_scale"], "unit_scale");
    if (!(scale > 0.0f)) throw InputError(path + ": unit_scale: must be > 0");
  }

  Scene scene = loadMesh(meshFile, options);  // validated; InputError names the mesh file
  const Reader r{path, scene};
  r.checkKeys(
      root, "",
      {"mesh", "unit_scale", "textures", "sky", "lights", "cameras", "fine_volumes", "materials", "comment"});

  if (scale != 1.0f) {
    for (glm::vec3& p : scene.positions) p *= scale;
    for (Light& l : scene.lights) {
      l.position *= scale;
      l.radius *= scale;
    }
    for (Camera& c : scene.cameras) {
      c.eye *= scale;
      c.target *= scale;
    }
  }

  if (root.contains("sky")) {
    const json& sky = r.object(root["sky"], "sky");
    r.checkKeys(sky, "sky", {"radiance", "zenith", "horizon"});
    if (sky.contains("radiance")) {
      if (sky.contains("zenith") || sky.contains("horizon"))
        r.fail("sky", "give either radiance or zenith + horizon, not both");
      scene.skyRadiance = r.colour(sky["radiance"], "sky.radiance");
    } else if (sky.contains("zenith") || sky.contains("horizon")) {
      if (!sky.contains("zenith") || !sky.contains("horizon"))
        r.fail("sky", "a gradient sky needs zenith and horizon");
      scene.skyRadiance = r.colour(sky["zenith"], "sky.zenith");
      scene.skyHorizonRadiance = r.colour(sky["horizon"], "sky.horizon");
    }
  }
  if (root.contains("lights")) {
    const json& lights = r.array(root["lights"], "lights");
    for (size_t i = 0; i < lights.size(); ++i)
      readLight(r, lights[i], "lights[" + std::to_string(i) + "]", scale);
  }
  if (root.contains("cameras")) {
    const json& cams = r.array(root["cameras"], "cameras");
    for (size_t i = 0; i < cams.size(); ++i)
      readCamera(r, cams[i], "cameras[" + std::to_string(i) + "]", scale);
  }
  if (root.contains("fine_volumes")) {
    const json& vols = r.array(root["fine_volumes"], "fine_volumes");
    for (size_t i = 0; i < vols.size(); ++i)
      readVolume(r, vols[i], "fine_volumes[" + std::to_string(i) + "]", scale);
  }
  if (root.contains("materials")) {
    const json& mats = r.object(root["materials"], "materials");
    for (auto it = mats.begin(); it != mats.end(); ++it)
      readMaterialOverride(r, it.key(), it.value(), "materials." + it.key());
  }
  return scene;
}

}  // namespace tetraprobe::detail
