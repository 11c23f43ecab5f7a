// `tetraprobe render SCENE LEVEL.tpb -o IMAGE`: a view lit per pixel by the probes, rendered headless through
// Vulkan (G-buffer raster, then the GLSL lookup pass of shaders/tetraprobe.glsl); or, at the same camera,
// the path-traced reference irradiance (--mode reference) and the probes' error against it (--mode error),
// both traced on the CPU with Embree (eval/reference_image.h, eval/error_image.h). --mode full adds the
// scene's point, spot and sun lights with shadow maps and the emitters; probes, tets and occlusion are debug
// views of the level.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "args.h"
#include "commands.h"
#include "render_view.h"
#include "stream_view.h"
#include "tetraprobe/bake/tracer.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/error_image.h"
#include "tetraprobe/eval/reference_image.h"
#include "tetraprobe/render/render.h"
#include "tetraprobe/runtime/query.h"
#include "tetraprobe/scene/load.h"

namespace tetraprobe::cli {

namespace {

// The renderer's modes by name.
bool gpuMode(const std::string& mode, RenderMode* out) {
  const std::pair<const char*, RenderMode> modes[] = {{"irradiance", RenderMode::kIrradiance},
                                                      {"indirect", RenderMode::kIndirect},
                                                      {"full", RenderMode::kFull},
                                                      {"probes", RenderMode::kProbes},
                                                      {"tets", RenderMode::kTets},
                                                      {"occlusion", RenderMode::kOcclusion}};
  for (const auto& [name, m] : modes)
    if (mode == name) {
      *out = m;
      return true;
    }
  return false;
}

// Options that only the traced modes (reference, error) take, and those only the GPU modes take.
constexpr const char* kTracedOnly[] = {"--samples", "--max-seconds", "--bounces", "--seed", "--threads"};
constexpr const char* kGpuOnly[] = {"--frames", "--shadow-map-size", "--half-res", "--stream-window"};

// Above this mean relative standard error the reference's own noise shows in the error image (0.1 is
// about 0.14 stops per pixel).
constexpr double kNoisyReference = 0.1;

int parseBounces(const std::string& text) {
  if (text == "unbounded") return kUnboundedBounces;
  const double b = parseNumber(text, "--bounces");
  if (!(b >= 0.0 && b <= double(kUnboundedBounces)) || b != std::floor(b))
    throw UsageError("--bounces must be 'unbounded' or a whole number >= 0, not '" + text + "'");
  return int(b);
}

// --mode reference / error: trace the reference at the view's pixels, write the image, print the summary.
void renderTraced(const Args& args, const Scene& scene, const Level& level, const RenderView& view,
                  const std::string& mode, const std::string& out) {
  ReferenceImageOptions opt;
  opt.samplesPerPixel = args.integer("--samples");
  opt.maxSeconds = args.number("--max-seconds");
  opt.bounces = parseBounces(args.str("--bounces"));
  opt.content = level.content;
  opt.seed = args.u64("--seed");
  opt.threads = args.integer("--threads");
  if (opt.samplesPerPixel < 1) throw UsageError("--samples must be at least 1");
  if (!(opt.maxSeconds >= 0.0)) throw UsageError("--max-seconds must be >= 0");
  if (opt.threads < 0) throw UsageError("--threads must be >= 0");
  for (const auto& w : scene.warnings) std::fprintf(stderr, "tetraprobe render: warning: %s\n", w.c_str());

  const SceneTracer tracer(scene);
  const ReferenceImage ref = renderReferenceImage(tracer, view, opt);
  const size_t hits = ref.gbuffer.hitCount();
  nlohmann::json report = {{"mode", mode},
                           {"width", view.width},
                           {"height", view.height},
                           {"hit_pixels", hits},
                           {"samples_per_pixel", ref.samplesPerPixel},
                           {"passes", ref.passes},
                           {"bounces", opt.bounces == kUnboundedBounces ? nlohmann::json("unbounded")
                                                                        : nlohmann::json(opt.bounces)},
                           {"reference_seconds", ref.seconds},
                           {"reference_mean_rel_stderr", ref.meanRelStderr()}};
  std::printf(
      "tetraprobe render: reference: %d paths per pixel (%d passes) at %zu of %d pixels in %.2fs; "
      "mean relative standard error %.2f %%\n",
      ref.samplesPerPixel, ref.passes, hits, view.width * view.height, ref.seconds,
      100.0 * ref.meanRelStderr());
  std::fflush(stdout);  // the summary before the warning about it, also when both go to one pipe
  if (ref.meanRelStderr() > kNoisyReference)
    std::fprintf(stderr,
                 "tetraprobe render: warning: the reference is noisy (mean relative standard error %.0f %%, "
                 "about %.2f stops in e per pixel): raise --samples before trusting single pixels\n",
                 100.0 * ref.meanRelStderr(), ref.meanRelStderr() / std::log(2.0));

  Image image;
  image.width = view.width;
  image.height = view.height;
  image.rgba.assign(size_t(view.width) * size_t(view.height) * 4, 0.0f);
  std::string error;
  if (mode == "reference") {
    for (size_t i = 0; i < ref.irradiance.size(); ++i) {
      if (!ref.gbuffer.hit[i]) continue;
      for (int c = 0; c < 3; ++c) image.rgba[4 * i + c] = ref.irradiance[i][c];
      image.rgba[4 * i + 3] = 1.0f;
    }
    if (endsWith(out, ".exr")) {
      if (!writeExr(out, image, &error)) throw std::runtime_error(error);
    } else {
      const float exposure =
          args.str("--exposure") == "auto" ? autoExposure(image) : float(args.number("--exposure"));
      if (!writePng(out, image, exposure, &error)) throw std::runtime_error(error);
    }
  } else {
    const ProbeQuery query(level);
    const std::vector<glm::vec3> lookup = probeLookupImage(query, ref.gbuffer, opt.threads);
    const ErrorImage err = computeErrorImage(ref.gbuffer, lookup, ref.irradiance);
    const ErrorStats& s = err.stats;
    if (endsWith(out, ".exr")) {
      if (!writeExr(out, errorValues(err), &error)) throw std::runtime_error(error);
    } else if (!writePngLinear(out, errorHeatMap(err), &error)) {
      throw std::runtime_error(error);
    }
    std::printf(
        "tetraprobe render: error: gross (off by > 2x) %.2f %% (too bright %.2f %%, too dark %.2f %%), "
        "dark holes (< 0.25x) %.2f %% of %zu pixels; mean log2(lookup/reference) %+.3f, mean |log2| "
        "%.3f\n",
        100.0 * s.gross, 100.0 * s.tooBright, 100.0 * s.tooDark, 100.0 * s.darkHoles, s.pixels, s.meanLog2,
        s.meanAbsLog2);
    report["error"] = {{"pixels", s.pixels},
                       {"gross_fraction", s.gross},
                       {"too_bright_fraction", s.tooBright},
                       {"too_dark_fraction", s.tooDark},
                       {"dark_hole_fraction", s.darkHoles},
                       {"mean_log2_ratio", s.meanLog2},
                       {"mean_abs_log2_ratio", s.meanAbsLog2},
                       {"definition",
                        "e = log2(max(Y(lookup), 0.01) / max(Y(reference), 0.01)), Y = Rec. 709 "
                        "luminance of irradiance in W/m^2; gross: |e| > 1; dark hole: e < -2"},
                       {"lookup", "CPU ProbeQuery::irradiance at the reference's hit points and normals"}};
  }
  if (args.has("--json")) writeJsonReport(args.str("--json"), report);
  std::printf("tetraprobe render: %s (%dx%d, %s)\n", out.c_str(), view.width, view.height, mode.c_str());
}

}  // namespace

int cmdRender(int argc, char** argv) {
  Args args(
      "tetraprobe render SCENE LEVEL.tpb -o IMAGE [options]",
      "Renders the scene lit per pixel by the level's probes (headless Vulkan; lavapipe works).\n"
      "IMAGE ending in .png is tone-mapped 8-bit sRGB; .exr is linear float RGBA.\n"
      "Modes: irradiance = E in W/m^2 (the light content the probes hold); indirect = albedo * E / pi;\n"
      "full = emission + albedo / pi * (E + direct irradiance from the scene's point, spot and sun lights,\n"
      "shadow-mapped: a 6-face cube per point/spot, one orthographic map per sun, 3x3 PCF), tone-mapped\n"
      "(Reinhard after --exposure); for levels baked with the default content (no direct punctual light).\n"
      "Debug views (fixed colours, no tone mapping): probes = probe dots by kind (surface green, volume\n"
      "cyan, open light blue, filler blue, shell orange, dilated magenta, hole red, refinement yellow,\n"
      "user white; hidden probes small and dim); tets = each pixel in its tet's colour, dark tet faces,\n"
      "outer cells dark; occlusion = the occlusion kind used (none grey, planes blue, shadow maps green),\n"
      "red where the all-occluded fallback ran.\n"
      "reference = the path-traced E (W/m^2, the level's light content) at the same pixels: the first\n"
      "front face the pixel-centre ray meets (back faces are stepped through, as Vulkan culls them),\n"
      "--samples paths per pixel of unbounded depth (Russian roulette), on the CPU (Embree);\n"
      "error = the probes' signed error against that reference, e = log2(max(Y(lookup), 0.01) /\n"
      "max(Y(reference), 0.01)) (Y: luminance in W/m^2; lookup: the CPU ProbeQuery at the same points),\n"
      "as a heat map with a fixed scale: e clamped to [-2, +2] (4x either way) through ColorBrewer RdBu,\n"
      "dark blue = probes 4x too dark, white = right, dark red = 4x too bright. It prints the fraction\n"
      "of pixels off by more than 2x either way (gross) and below 0.25x (dark holes).\n"
      "Background pixels are black in every mode; reference and error need no GPU.\n"
      "With .exr: reference = linear E, error = e (the same in r, g, b).\n"
      "--json FILE with a GPU mode: GPU milliseconds per pass from Vulkan timestamp queries, the median\n"
      "of --frames frames after 2 warm-up frames.",
      withViewOptions(
          {{"--output", "-o", "IMAGE", "image to write (.png or .exr)", ""},
           {"--size", "", "WxH", "image size in pixels", "960x540"},
           {"--mode", "", "irradiance|indirect|full|probes|tets|occlusion|reference|error",
            "what the pixels show", "indirect"},
           {"--exposure", "", "auto|X", "PNG exposure multiplier before tone mapping (not for error)",
            "auto"},
           {"--samples", "", "N", "reference/error: paths per pixel", "64"},
           {"--max-seconds", "", "S", "reference/error: stop after the pass that ends past S s (0 = none)",
            "0"},
           {"--bounces", "", "unbounded|N", "reference/error: path depth", "unbounded"},
           {"--seed", "", "N", "reference/error: random seed (same seed and passes: same image)", "1"},
           {"--threads", "", "N", "reference/error: worker threads, 0 = all cores (never changes it)", "0"},
           {"--json", "", "FILE", "write the figures printed as JSON (GPU modes: per-pass GPU times)", ""},
           {"--frames", "", "N", "GPU modes: timed frames (median; with --json 2 warm-up frames before)",
            "9"},
           {"--shadow-map-size", "", "N", "full: texels per side of each shadow-map layer", "1024"},
           {"--half-res", "", "",
            "irradiance/indirect: the half-resolution lookup an engine may choose (one lookup a 2x2 block,\n"
            "upsampled by depth and normal, full lookups where no sample matches; shaders/"
            "tetraprobe_upsample.glsl)",
            ""},
           {"--stream-window", "", "N",
            "irradiance/indirect/full, a level with a streaming index (tetraprobe stream): the lookup reads\n"
            "a GPU sector pool holding the N sectors nearest the view's target, as an engine streaming the\n"
            "level shows it (the coarse set elsewhere); prints how many pixels come from loaded sectors and\n"
            "that they equal the full level's (docs/streaming.md)",
            ""}}));
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(2, 2);
  if (!args.has("--output")) throw UsageError("missing -o IMAGE");
  const std::string out = args.str("--output");
  if (!endsWith(out, ".png") && !endsWith(out, ".exr")) throw UsageError("IMAGE must end in .png or .exr");

  RenderView view;
  const std::string size = args.str("--size");
  if (std::sscanf(size.c_str(), "%dx%d", &view.width, &view.height) != 2 || view.width < 1 ||
      view.height < 1 || view.width > 16384 || view.height > 16384)
    throw UsageError("--size must be WxH with 1..16384 pixels a side, not '" + size + "'");
  const std::string mode = args.str("--mode");
  const bool traced = mode == "reference" || mode == "error";
  if (traced)
    view.mode = RenderMode::kIndirect;
  else if (!gpuMode(mode, &view.mode))
    throw UsageError(
        "--mode must be irradiance, indirect, full, probes, tets, occlusion, reference or error, not '" +
        mode + "'");
  if (!traced)
    for (const char* name : kTracedOnly)
      if (args.has(name)) throw UsageError(std::string(name) + " applies to --mode reference and error only");
  if (traced)
    for (const char* name : kGpuOnly)
      if (args.has(name)) throw UsageError(std::string(name) + " does not apply to --mode " + mode);
  if ((mode == "error" || isDebugMode(view.mode)) && args.has("--exposure"))
    throw UsageError("--exposure does not apply to --mode " + mode + " (its colours are fixed)");
  if (args.has("--shadow-map-size") && view.mode != RenderMode::kFull)
    throw UsageError("--shadow-map-size applies to --mode full only");
  if (args.has("--half-res") && !(view.mode == RenderMode::kIrradiance || view.mode == RenderMode::kIndirect))
    throw UsageError("--half-res applies to --mode irradiance and indirect only");
  if (args.has("--stream-window") && !(view.mode == RenderMode::kIrradiance ||
                                       view.mode == RenderMode::kIndirect || view.mode == RenderMode::kFull))
    throw UsageError("--stream-window applies to --mode irradiance, indirect and full only");
  const int streamWindow = args.has("--stream-window") ? args.integer("--stream-window") : 0;
  if (args.has("--stream-window") && (streamWindow < 1 || streamWindow > 65536))
    throw UsageError("--stream-window must be in 1..65536");
  RenderOptions options;
  options.halfResolution = args.has("--half-res");
  if (!traced) {
    options.shadowMapSize = args.integer("--shadow-map-size");
    if (options.shadowMapSize < 16 || options.shadowMapSize > 8192)
      throw UsageError("--shadow-map-size must be in 16..8192");
    // Timing: without --json one frame (or --frames); with it 2 warm-up frames, then --frames.
    if (args.has("--json") || args.has("--frames")) {
      options.timedFrames = args.integer("--frames");
      if (options.timedFrames < 1 || options.timedFrames > 500)
        throw UsageError("--frames must be in 1..500");
      options.warmupFrames = args.has("--json") ? 2 : 0;
    }
  }

  const Scene scene = loadScene(args.positional()[0]);
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[1], level); !r) throw InputError(r.message);

  chooseView(args, scene, view);

  if (traced) {
    renderTraced(args, scene, level, view, mode, out);
    return 0;
  }

  const ProbeQuery query(level);
  if (view.mode == RenderMode::kFull) {
    options.lights = toRenderLights(scene);
    if (level.content & kContentDirectPunctual)
      std::fprintf(stderr,
                   "tetraprobe render: warning: the level's probes hold direct light from the lights "
                   "(--content all): --mode full counts it twice\n");
  }
  if (view.mode == RenderMode::kProbes && level.probeKinds.empty())
    std::fprintf(stderr,
                 "tetraprobe render: warning: the level records no probe kinds (baked before they were "
                 "stored): every probe is drawn white\n");
  // --stream-window: the pool's buffers in place of the level's, and the full level's render to compare.
  std::unique_ptr<StreamView> stream;
  if (streamWindow > 0) {
    stream = openStreamView(args.positional()[1], size_t(streamWindow), glm::dvec3(view.target));
    options.levelBuffers = &stream->pool.buffers();
    options.variant = stream->pool.variant();
  }
  const auto t0 = std::chrono::steady_clock::now();
  RenderResult result = renderLevel(toRenderMesh(scene), level, query, view, options);
  if (stream) {
    RenderOptions fullOptions = options;
    fullOptions.levelBuffers = nullptr;
    fullOptions.variant.reset();
    const RenderResult full = renderLevel(toRenderMesh(scene), level, query, view, fullOptions);
    const StreamViewPixels n = compareStreamView(*stream, level.origin, full, result);
    std::printf(
        "tetraprobe render: streamed: %zu of %zu sectors loaded into a %zu-byte GPU pool; %zu geometry "
        "pixels from loaded sectors (%zu equal to the full level's), %zu from the coarse set\n",
        stream->pool.loadedSectors(), stream->level.sectors().size(), stream->pool.bytes(), n.loaded,
        n.identical, n.coarse);
    if (n.identical != n.loaded)
      throw std::runtime_error("streamed pixels differ from the full level's where their sector is loaded");
  }
  if (options.halfResolution) {  // the image written: the half-resolution answer, a = 1 on geometry
    result.color = std::move(result.halfResolution);
    for (size_t i = 3; i < result.color.rgba.size(); i += 4)
      result.color.rgba[i] = result.color.rgba[i] != 0.0f;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::string error;
  if (endsWith(out, ".exr")) {
    if (!writeExr(out, result.color, &error)) throw std::runtime_error(error);
  } else if (isDebugMode(view.mode)) {
    if (!writePngLinear(out, result.color, &error)) throw std::runtime_error(error);
  } else {
    const float exposure =
        args.str("--exposure") == "auto" ? autoExposure(result.color) : float(args.number("--exposure"));
    if (!writePng(out, result.color, exposure, &error)) throw std::runtime_error(error);
  }
  std::string passes;
  for (const PassTiming& p : result.timings.passes) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s%s %.2f ms", passes.empty() ? "" : ", ", p.name.c_str(), p.ms);
    passes += buf;
  }
  std::printf("tetraprobe render: %s (%dx%d, %s) in %.2fs; GPU (median of %d frame%s): %s\n", out.c_str(),
              view.width, view.height, mode.c_str(), seconds, result.timings.timedFrames,
              result.timings.timedFrames == 1 ? "" : "s", passes.empty() ? "no timestamps" : passes.c_str());
  if (args.has("--json")) {
    nlohmann::json gpu = nlohmann::json::object();
    for (const PassTiming& p : result.timings.passes) gpu[p.name] = p.ms;
    nlohmann::json report = {{"mode", mode},
                             {"width", view.width},
                             {"height", view.height},
                             {"lights", options.lights.size()},
                             {"variant", result.variant.name()},
                             {"warmup_frames", result.timings.warmupFrames},
                             {"timed_frames", result.timings.timedFrames},
                             {"gpu_ms", gpu},
                             {"gpu_ms_definition",
                              "per pass, the median over the timed frames of the difference between Vulkan "
                              "timestamps written after the pass (and a barrier) and after the one before"},
                             {"seconds", seconds}};
    writeJsonReport(args.str("--json"), report);
  }
  return 0;
}

}  // namespace tetraprobe::cli
