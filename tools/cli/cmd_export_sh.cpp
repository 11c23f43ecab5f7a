// `tetraprobe export-sh LEVEL.tpb -o FILE.csv`: a level's probes (world positions) and SH as the CSV that
// `tetraprobe bake --import-sh` reads (bake/include/tetraprobe/bake/sh_csv.h), so SH can round-trip.
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "tetraprobe/bake/sh_csv.h"
#include "tetraprobe/common/error.h"
#include "tetraprobe/runtime/level.h"

namespace tetraprobe::cli {

int cmdExportSh(int argc, char** argv) {
  Args args(
      "tetraprobe export-sh LEVEL.tpb -o FILE.csv",
      "Writes every probe of a level as one CSV line: world x,y,z (metres) then its 27 SH coefficients,\n"
      "coefficient-major r,g,b, index l*(l+1)+m, incident radiance W/(m^2 sr). The format\n"
      "`tetraprobe bake --import-sh` reads; positions print with 17 digits, coefficients with 9, so\n"
      "an export, import and export again gives the same file.",
      {{"--output", "-o", "FILE.csv", "CSV file to write (atomically)", ""}});
  if (!args.parse(argc, argv)) return 0;
  args.requirePositional(1, 1);
  if (!args.has("--output")) throw UsageError("missing -o FILE.csv");
  Level level;
  if (const LevelResult r = loadLevel(args.positional()[0], level); !r) throw InputError(r.message);
  ProbeShTable table;
  table.positions.reserve(level.probes.size());
  for (const glm::vec3& p : level.probes) table.positions.push_back(level.origin + glm::dvec3(p));
  table.sh = level.sh;
  writeShCsv(args.str("--output"), table);
  std::printf("tetraprobe export-sh: %zu probes (L%u) -> %s\n", level.probes.size(), level.shOrder,
              args.str("--output").c_str());
  return 0;
}

}  // namespace tetraprobe::cli
