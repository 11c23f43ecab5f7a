// JSON report output, written atomically.
#include <stdexcept>

#include "commands.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe::cli {

void writeJsonReport(const std::string& path, const nlohmann::json& report) {
  std::string error;
  if (!writeFileAtomic(path, report.dump(2) + "\n", &error)) throw std::runtime_error(error);
}

}  // namespace tetraprobe::cli
