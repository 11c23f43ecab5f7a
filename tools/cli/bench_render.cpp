// `tetraprobe bench render SCENE LEVEL`: the GPU cost of the per-pixel tet lookup against its peers in one run,
// on the same G-buffer: the lookup pass in every shader variant that covers the level (runtime/
// shader_variant.h), a pass writing a constant (the floor of any full-screen pass) and a trilinear SH L2 grid
// read from 3D textures with hardware filtering, of the tet level's bytes (what an engine's irradiance volume
// costs). Times are GPU timestamps around each pass, the median of --frames frames after 2 warm-up frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "half_resolution_report.h"
#include "render_view.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/eval/grid_volume.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/runtime/shader_variant.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

constexpr double kLookupGoalRatio = 1.5;  // issue #13: lookup_ms <= 1.5 x grid_ms on lavapipe

// The grid's nodes hold the level's own SH, blended at each node as the lookup blends it (no normal, so no
// occlusion): the texture pass then shows the same light field. Timing does not depend on the values.
std::vector<ShRgb> gridFromLevel(const ProbeQuery& query, const GridLayout& layout) {
  const Level& level = query.level();
  std::vector<ShRgb> sh(layout.nodes());
  int32_t hint = -1;
  for (size_t n = 0; n < sh.size(); ++n) {
    const Location loc = query.locate(layout.node(n), hint);
    if (loc.tet < 0) continue;
    hint = loc.tet;
    const ShRgb* probes[4];
    for (int i = 0; i < 4; ++i) probes[i] = &level.sh[size_t(level.tets[size_t(loc.tet)].v[i])];
    const float w[4] = {loc.weights[0], loc.weights[1], loc.weights[2], loc.weights[3]};
    sh[n] = shBlend(probes, w, 4);
  }
  return sh;
}

// The median over every pass of the render named one of `names` (a path repeats them; 0 when none).
double medianMs(const RenderResult& r, std::initializer_list<const char*> names) {
  std::vector<double> ms;
  for (const PassTiming& p : r.timings.passes)
    for (const char* n : names)
      if (p.name == n) ms.push_back(p.ms);
  if (ms.empty()) return 0.0;
  std::sort(ms.begin(), ms.end());
  return ms.size() % 2 ? ms[ms.size() / 2] : 0.5 * (ms[ms.size() / 2 - 1] + ms[ms.size() / 2]);
}

// The largest relative difference, per channel, between two renders' geometry pixels (floor 1e-6).
double maxRelativeDifference(const Image& a, const Image& b) {
  double worst = 0.0;
  for (size_t i = 0; i + 3 < a.rgba.size() && i + 3 < b.rgba.size(); i += 4) {
    if (a.rgba[i + 3] == 0.0f) continue;
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(double(a.rgba[i + c]) - b.rgba[i + c]) /
                                  std::max(std::abs(double(a.rgba[i + c])), 1e-6));
  }
  return worst;
}

}  // namespace

int benchRender(int argc, char** argv) {
  Args args(
      "tetraprobe bench render SCENE LEVEL.tpb [--size 1280x720] [--camera NAME | --eye X,Y,Z --target "
      "X,Y,Z]\n"
      "                        [--frames 9] [--json]",
      "Times, on one G-buffer of the scene's view, GPU passes writing E per pixel: the tet lookup\n"
      "(lighting.comp) in every shader variant that covers the level (the level's own first; ambient =\n"
      "a constant, the floor of a full-screen pass; grid = a regular SH L2 grid over the scene's box, of\n"
      "at most the tet lookup's bytes at 56 bytes a node (half-precision SH as a level stores them, as "
      "`eval`\n"
      "sizes its equal-bytes grid), holding\n"
      "the level's SH blended at each node, read from seven 3D textures with hardware trilinear filtering).\n"
      "Each time is the median over --frames frames after 2 warm-up frames of Vulkan timestamps around\n"
      "the pass. The goal on lavapipe: the level's lookup_ms <= 1.5 x grid_ms. Apart (an engine option, not\n"
      "the goal's figure): the half-resolution lookup (one lookup a 2x2 block, then a depth- and "
      "normal-aware\n"
      "upsample, then full lookups at the pixels no sample matches), its three passes' times and its\n"
      "difference from the full-resolution lookup per pixel (shaders/tetraprobe_upsample.glsl).",
      withViewOptions({{"--size", "", "WxH", "image size in pixels", "1280x720"},
                       {"--frames", "", "N", "timed frames (median), after 2 warm-up frames", "9"},
                       {"--also", "", "V1,V2",
                        "more variants to time, named as printed (e.g. l2+outer+cells), even ones that "
                        "leave out what the level uses (their pixels are then wrong): to profile the lookup",
                        ""},
                       {"--temporal-frames", "", "N",
                        "frames of the camera path for the temporal start (the walk from last frame's tet "
                        "of the pixel, reprojected), ending at the view; 0 = off",
                        "4"},
                       {"--temporal-step", "", "M",
                        "metres the camera moves a frame along the path, sideways (to its right)", "0.03"},
                       {"--json", "", "", "print the figures as one JSON object", ""}}));
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  RenderView view;
  view.mode = RenderMode::kIrradiance;
  const std::string size = args.str("--size");
  if (std::sscanf(size.c_str(), "%dx%d", &view.width, &view.height) != 2 || view.width < 1 ||
      view.height < 1 || view.width > 16384 || view.height > 16384)
    throw UsageError("--size must be WxH with 1..16384 pixels a side, not '" + size + "'");
  RenderOptions options;
  options.warmupFrames = 2;
  options.timedFrames = args.integer("--frames");
  if (options.timedFrames < 1 || options.timedFrames > 500) throw UsageError("--frames must be in 1..500");

  const Scene scene = loadScene(args.positional()[0]);
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[1], level); !r) throw InputError(r.message);
  if (level.tets.empty()) throw InputError("the level has no tets: nothing to look up");
  chooseView(args, scene, view);

  const ProbeQuery query(level);
  const ShaderVariant chosen = shaderVariantFor(level, query.outerCells(), query.cellGrid());
  options.variant = chosen;
  options.benchVariants = coveringShaderVariants(chosen);
  if (args.has("--also")) {
    std::string list = args.str("--also") + ",";
    for (size_t start = 0, end; (end = list.find(',', start)) != std::string::npos; start = end + 1) {
      const std::string name = list.substr(start, end - start);
      ShaderVariant v;
      if (!parseShaderVariant(name, v))
        throw UsageError("--also: '" + name + "' is not a variant name (e.g. l2+planes+outer+cells)");
      if (std::find(options.benchVariants.begin(), options.benchVariants.end(), v) ==
          options.benchVariants.end())
        options.benchVariants.push_back(v);
    }
  }
  options.benchAmbient = true;
  options.halfResolution = true;
  options.temporalFrames = args.integer("--temporal-frames");
  if (options.temporalFrames != 0 && (options.temporalFrames < 2 || options.temporalFrames > 32))
    throw UsageError("--temporal-frames must be 0 or in 2..32");
  const double temporalStep = args.number("--temporal-step");
  if (!(temporalStep >= 0.0 && temporalStep <= 10.0)) throw UsageError("--temporal-step must be in 0..10 m");

  const uint64_t tetBytes = totalBytes(tetLookupBytes(query, !level.occlusion.empty()));
  glm::vec3 lo, hi;
  sceneBounds(scene, lo, hi);
  const GridLayout layout = gridLayoutForBytes(glm::dvec3(lo), glm::dvec3(hi), tetBytes);
  const std::vector<ShRgb> gridSh = gridFromLevel(query, layout);
  RenderGrid grid;
  grid.min = layout.min;
  grid.step = layout.step;
  grid.dims = layout.dims;
  grid.sh = gridSh.data();
  options.benchGrid = &grid;

  if (options.temporalFrames > 0) {  // sideways: the camera's right, eye and target together
    const glm::vec3 forward = glm::normalize(view.target - view.eye);
    options.temporalStep = float(temporalStep) * glm::normalize(glm::cross(forward, view.up));
  }
  const RenderResult r = renderLevel(toRenderMesh(scene), level, query, view, options);
  if (r.timings.passes.empty()) throw std::runtime_error("bench render: the Vulkan queue has no timestamps");

  nlohmann::json lookup = nlohmann::json::object();
  const double chosenMs = r.timings.passMs("lookup:" + chosen.name());
  lookup["chosen"] = chosenMs;
  for (const ShaderVariant& v : options.benchVariants)
    lookup[v.name()] = r.timings.passMs("lookup:" + v.name());
  const double ambientMs = r.timings.passMs("ambient"), gridMs = r.timings.passMs("grid_texture");
  const double ratio = gridMs > 0.0 ? chosenMs / gridMs : 0.0;
  const bool met = gridMs > 0.0 && ratio <= kLookupGoalRatio;
  const HalfResolutionReport half = halfResolutionReport(r, chosenMs, gridMs);
  nlohmann::json temporalJson = nullptr;
  double coldMs = 0.0, warmMs = 0.0, temporalDiff = 0.0, heldShare = 0.0;
  if (options.temporalFrames > 0) {
    coldMs = medianMs(r, {"lookup_cold", "lighting"});
    warmMs = medianMs(r, {"lookup_temporal"});
    temporalDiff = maxRelativeDifference(r.color, r.temporal);
    size_t pixels = 0, kept = 0;
    for (size_t i = 3; i < r.temporal.rgba.size(); i += 4) {
      pixels += r.temporal.rgba[i] != 0.0f;
      kept += r.temporal.rgba[i] == 2.0f;
    }
    heldShare = pixels ? double(kept) / double(pixels) : 0.0;
    temporalJson = {
        {"frames", options.temporalFrames},
        {"step_m", temporalStep},
        {"cold_ms", coldMs},
        {"temporal_ms", warmMs},
        {"ratio_to_cold", coldMs > 0.0 ? warmMs / coldMs : 0.0},
        {"ratio_to_grid", gridMs > 0.0 ? warmMs / gridMs : 0.0},
        {"max_rel_difference_to_cold", temporalDiff},
        {"pixels_held_by_previous_tet", heldShare},
        {"definition",
         "the level's variant on each frame of a sideways camera path ending at the view: cold = "
         "median of the lookup from the start bricks over the path's frames, temporal = median of "
         "the lookup started from the previous frame's tet of the reprojected pixel (the path's "
         "first frame, which has none, left out)"}};
  }
  size_t geometry = 0;
  for (size_t i = 0; i < r.position.rgba.size(); i += 4) geometry += r.position.rgba[i + 3] != 0.0f;

  if (args.has("--json")) {
    const nlohmann::json j = {
        {"scene", args.positional()[0]},
        {"level", args.positional()[1]},
        {"width", view.width},
        {"height", view.height},
        {"geometry_pixels", geometry},
        {"device", r.deviceName},
        {"warmup_frames", r.timings.warmupFrames},
        {"timed_frames", r.timings.timedFrames},
        {"variant", chosen.name()},
        {"lookup_ms", lookup},
        {"ambient_ms", ambientMs},
        {"grid_ms", gridMs},
        {"gbuffer_ms", r.timings.gbufferMs},
        {"grid",
         {{"dims", {layout.dims.x, layout.dims.y, layout.dims.z}},
          {"step_m", layout.step},
          {"node_bytes", kGridNodeBytes},
          {"bytes", layout.bytes()},
          {"texture_format", r.gridTextureFormat},
          {"texture_bytes", r.gridTextureBytes}}},
        {"tet_lookup_bytes", tetBytes},
        {"ratio_lookup_to_grid", ratio},
        {"goal_ratio", kLookupGoalRatio},
        {"goal_met", met},
        {"half_resolution", halfResolutionJson(half)},
        {"temporal", temporalJson},
        {"ms_definition",
         "per pass, the median over the timed frames of the difference between Vulkan timestamps before "
         "and after the pass, each pass in a command buffer of its own on the same G-buffer"}};
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("bench render: %dx%d (%zu geometry pixels) on %s, median of %d frames after %d warm-up\n",
              view.width, view.height, geometry, r.deviceName.c_str(), r.timings.timedFrames,
              r.timings.warmupFrames);
  for (const ShaderVariant& v : options.benchVariants)
    std::printf("  lookup %-38s %9.3f ms%s\n", v.name().c_str(), r.timings.passMs("lookup:" + v.name()),
                v == chosen                      ? "  (the level's)"
                : shaderVariantCovers(v, chosen) ? ""
                                                 : "  (does not cover the level: profiling only)");
  std::printf("  ambient (a constant)                          %9.3f ms\n", ambientMs);
  std::printf(
      "  grid (3D textures)                            %9.3f ms  (%dx%dx%d nodes of %.3g m, %s, %.2f MB)\n",
      gridMs, layout.dims.x, layout.dims.y, layout.dims.z, layout.step, r.gridTextureFormat.c_str(),
      double(r.gridTextureBytes) / 1e6);
  std::printf("  tet lookup bytes %.2f MB; lookup / grid = %.2f (goal <= %.1f: %s)\n", double(tetBytes) / 1e6,
              ratio, kLookupGoalRatio, met ? "met" : "NOT met");
  printHalfResolution(half);
  if (options.temporalFrames > 0)
    std::printf(
        "  temporal start (engine option)                %9.3f ms  (cold %.3f on the same path of %d frames, "
        "%.3g m a frame: %.2f x cold, %.2f x grid; %.1f %% of pixels held by last frame's tet; largest "
        "difference to cold %.2g)\n",
        warmMs, coldMs, options.temporalFrames, temporalStep, coldMs > 0.0 ? warmMs / coldMs : 0.0,
        gridMs > 0.0 ? warmMs / gridMs : 0.0, 100 * heldShare, temporalDiff);
  return 0;
}

}  // namespace tetraprobe::cli
