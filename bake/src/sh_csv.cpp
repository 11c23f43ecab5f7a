// Reader and writer of the probe SH CSV format (tetraprobe/bake/sh_csv.h). The reader is meant for files
// from other tools: every field is checked and errors name the file and line.
#include "tetraprobe/bake/sh_csv.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "tetraprobe/common/error.h"
#include "tetraprobe/common/text.h"
#include "tetraprobe/runtime/file_io.h"

namespace tetraprobe {

namespace {

constexpr int kFields = 3 + 3 * kShCoeffCount;
static_assert(kFields == 30, "x,y,z + 27 coefficients");

bool parseFiniteFloat(std::string_view field, float& out) {
  field = trimWhitespace(field);
  if (field.empty()) return false;
  if (field.front() == '+') field.remove_prefix(1);
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), out);
  return ec == std::errc() && end == field.data() + field.size() && std::isfinite(out);
}

std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> fields;
  while (true) {
    const size_t comma = s.find(',');
    fields.push_back(s.substr(0, comma));
    if (comma == std::string_view::npos) break;
    s.remove_prefix(comma + 1);
  }
  return fields;
}

}  // namespace

ProbeShTable parseShCsv(const std::string& text, const std::string& source) {
  ProbeShTable table;
  std::string_view rest = text;
  bool firstRecord = true;
  for (size_t lineNo = 1; !rest.empty(); ++lineNo) {
    const size_t nl = rest.find('\n');
    const std::string_view line = trimWhitespace(rest.substr(0, nl));
    rest.remove_prefix(nl == std::string_view::npos ? rest.size() : nl + 1);
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> fields = split(line);
    const std::string where = source + ":" + std::to_string(lineNo) + ": ";
    double first = 0.0;
    if (firstRecord && !parseFiniteField(fields[0], first)) {
      firstRecord = false;  // a header line
      continue;
    }
    firstRecord = false;
    if (fields.size() != size_t(kFields))
      throw InputError(where + "expected 30 comma-separated values (x,y,z and 27 SH coefficients), found " +
                       std::to_string(fields.size()));
    glm::dvec3 p;
    for (int k = 0; k < 3; ++k)
      if (!parseFiniteField(fields[size_t(k)], p[k]))
        throw InputError(where + "field " + std::to_string(k + 1) + " '" +
                         std::string(trimWhitespace(fields[size_t(k)])) +
                         "' is not a finite number (position, metres)");
    ShRgb sh;
    for (int k = 3; k < kFields; ++k) {
      const int i = (k - 3) / 3, c = (k - 3) % 3;
      if (!parseFiniteFloat(fields[size_t(k)], sh.c[size_t(i)][c]))
        throw InputError(
            where + "field " + std::to_string(k + 1) + " '" + std::string(trimWhitespace(fields[size_t(k)])) +
            "' is not a finite float (SH coefficient " + std::to_string(i) + ", channel " + "rgb"[c] + ")");
    }
    table.positions.push_back(p);
    table.sh.push_back(sh);
  }
  return table;
}

ProbeShTable readShCsv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open SH CSV");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path + ": read failed");
  return parseShCsv(buffer.str(), path);
}

std::string formatShCsv(const ProbeShTable& table) {
  if (table.positions.size() != table.sh.size())
    throw InputError("SH CSV: " + std::to_string(table.positions.size()) + " positions but " +
                     std::to_string(table.sh.size()) + " SH");
  std::string out =
      "# tetraprobe probe SH: x,y,z (m) then 27 coefficients, coefficient-major r,g,b, index l*(l+1)+m, "
      "incident radiance W/(m^2 sr)\n";
  out += kShCsvHeader;
  out += '\n';
  char buf[64];
  for (size_t p = 0; p < table.positions.size(); ++p) {
    for (int k = 0; k < 3; ++k) {
      std::snprintf(buf, sizeof buf, "%.17g,", table.positions[p][k]);
      out += buf;
    }
    for (int i = 0; i < kShCoeffCount; ++i)
      for (int c = 0; c < 3; ++c) {
        std::snprintf(buf, sizeof buf, "%.9g,", double(table.sh[p].c[size_t(i)][c]));
        out += buf;
      }
    out.back() = '\n';
  }
  return out;
}

void writeShCsv(const std::string& path, const ProbeShTable& table) {
  std::string error;
  if (!writeFileAtomic(path, formatShCsv(table), &error)) throw std::runtime_error(error);
}

}  // namespace tetraprobe
