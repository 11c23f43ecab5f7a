// `tetraprobe inspect LEVEL.tpb [--json]`: what a level file holds.
#include <cstdio>
#include <filesystem>

#include <glm/common.hpp>

#include "args.h"
#include "commands.h"
#include "file_sections.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/eval/evaluate.h"
#include "tetraprobe/runtime/file_io.h"
#include "tetraprobe/runtime/level.h"
#include "tetraprobe/runtime/shader_variant.h"

namespace tetraprobe::cli {
int cmdInspect(int argc, char** argv) {
  Args args("tetraprobe inspect LEVEL.tpb [--json]", "Prints the contents of a level file.",
            {{"--json", "", "", "print JSON instead of text", ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1);
  const std::string path = args.positional()[0];
  Level level;
  if (const LevelResult r = loadLevel(path, level); !r) throw InputError(r.message);

  glm::vec3 lo(0.0f), hi(0.0f);
  if (!level.probes.empty()) lo = hi = level.probes[0];
  for (const auto& p : level.probes) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const glm::dvec3 wlo = level.origin + glm::dvec3(lo), whi = level.origin + glm::dvec3(hi);
  int hull = 0;
  for (const auto& t : level.tets)
    for (int i = 0; i < 4; ++i) hull += t.n[i] < 0;
  std::string content;
  if (level.content & kContentEmissive) content += "emissive ";
  if (level.content & kContentSky) content += "sky ";
  if (level.content & kContentIndirect) content += "indirect ";
  if (level.content & kContentDirectPunctual) content += "direct-punctual ";
  if (!content.empty()) content.pop_back();
  const uint64_t bytes = std::filesystem::file_size(path);
  const CellGrid& grid = level.cellGrid;
  const size_t cells = occupiedCells(grid), gridBytes = cellGridBytes(grid);
  // What the lookup touches, by section (the query builds the outer cells, cell grid and start grid the
  // level does not store, as an engine's load does).
  const ProbeQuery query(level);
  const std::vector<ByteSection> sections = tetLookupBytes(query, true);
  const uint64_t lookupBytes = totalBytes(sections);
  // The GLSL lookup's variant for this level (what an engine specializes its pipeline with).
  const std::string variant = shaderVariantFor(level, query.outerCells(), query.cellGrid()).name();
  const double probes = level.probes.empty() ? 1.0 : double(level.probes.size());
  nlohmann::json lookup = {{"total", lookupBytes}, {"per_probe", double(lookupBytes) / probes}};
  for (const ByteSection& s : sections)
    lookup["sections"][s.name] = {{"bytes", s.bytes}, {"per_probe", double(s.bytes) / probes}};
  // What the file stores, by section (tets without neighbours, no outer cells: the load derives them).
  const std::vector<FileSection> stored = fileSections(path);
  nlohmann::json file = {{"total", bytes}, {"per_probe", double(bytes) / probes}};
  for (const FileSection& s : stored)
    file["sections"][s.tag] = {{"bytes", s.bytes}, {"per_probe", double(s.bytes) / probes}};

  // Probes by kind (Level::probeKinds), when the level records them.
  nlohmann::json kinds = nlohmann::json::object();
  std::string kindText;
  if (!level.probeKinds.empty()) {
    size_t counts[kLevelProbeKindCount] = {};
    for (LevelProbeKind k : level.probeKinds) ++counts[uint8_t(k)];
    for (uint32_t k = 0; k < kLevelProbeKindCount; ++k) {
      if (counts[k] == 0) continue;
      const char* name = levelProbeKindName(LevelProbeKind(k));
      kinds[name] = counts[k];
      kindText += (kindText.empty() ? "" : ", ") + std::to_string(counts[k]) + " " + name;
    }
  }

  if (args.has("--json")) {
    nlohmann::json j = {{"path", path},
                        {"bytes", bytes},
                        {"generator", level.generator},
                        {"content", content},
                        {"sh_order", level.shOrder},
                        {"origin", {level.origin.x, level.origin.y, level.origin.z}},
                        {"bounds", {{"min", {wlo.x, wlo.y, wlo.z}}, {"max", {whi.x, whi.y, whi.z}}}},
                        {"probes", {{"count", level.probes.size()}, {"kinds", kinds}}},
                        {"tets", {{"count", level.tets.size()}, {"hull_faces", hull}}},
                        {"outer_cells", query.outerCells().size()},
                        {"outer_cells_stored", !level.outerCells.empty()},
                        {"locate",
                         {{"stored", !grid.slots.empty()},
                          {"cell_size_m", grid.cellSize},
                          {"cells", cells},
                          {"bsp_nodes", grid.nodes.size()},
                          {"leaves", grid.leaves},
                          {"max_depth", grid.maxDepth},
                          {"mean_depth", grid.meanDepth},
                          {"bytes", gridBytes}}},
                        {"occlusion_bytes", level.occlusion.bytes()},
                        {"lookup_bytes", lookup},
                        {"file_bytes", file},
                        {"shader_variant", variant}};
    std::printf("%s\n", j.dump(2).c_str());
    return 0;
  }
  std::printf("%s\n", path.c_str());
  std::printf("  bytes      %llu in the file, %.0f per probe:", (unsigned long long)bytes,
              double(bytes) / probes);
  for (const FileSection& s : stored) std::printf(" %s %.0f", s.tag.c_str(), double(s.bytes) / probes);
  std::printf("\n");
  std::printf("  generator  %s\n", level.generator.c_str());
  std::printf("  content    %s\n", content.c_str());
  std::printf("  SH order   L%u (RGB, %d coefficients)\n", level.shOrder, kShCoeffCount);
  std::printf("  origin     %.6g %.6g %.6g\n", level.origin.x, level.origin.y, level.origin.z);
  std::printf("  bounds     [%.4g %.4g %.4g] .. [%.4g %.4g %.4g]\n", wlo.x, wlo.y, wlo.z, whi.x, whi.y,
              whi.z);
  std::printf("  probes     %zu (%s)\n", level.probes.size(),
              kindText.empty() ? "kinds not recorded" : kindText.c_str());
  std::printf("  tets       %zu (%d hull faces), %zu outer cells%s\n", level.tets.size(), hull,
              query.outerCells().size(), level.outerCells.empty() ? " (built on load)" : "");
  if (grid.slots.empty())
    std::printf("  locate     no cell grid stored (built on load)\n");
  else
    std::printf(
        "  locate     %zu cells of %g m, BSP %zu nodes, %zu leaves, depth max %d mean %.1f, %zu bytes\n",
        cells, double(grid.cellSize), grid.nodes.size(), grid.leaves, grid.maxDepth, grid.meanDepth,
        gridBytes);
  std::printf("  occlusion  %zu bytes\n", level.occlusion.bytes());
  std::printf("  shader     variant %s\n", variant.c_str());
  // SH count as stored and uploaded (half precision); the CPU runtime decodes them to floats at load.
  std::printf("  lookup     %llu bytes on the GPU (the CPU's float SH: +52 per probe), %.0f per probe:",
              (unsigned long long)lookupBytes, double(lookupBytes) / probes);
  for (const ByteSection& s : sections) std::printf(" %s %.0f", s.name.c_str(), double(s.bytes) / probes);
  std::printf("\n");
  return 0;
}

}  // namespace tetraprobe::cli
