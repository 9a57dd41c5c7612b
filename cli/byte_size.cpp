#include <scan2lod/cli/byte_size.h>

#include <cctype>
#include <cmath>
#include <cstdlib>

namespace scan2lod::cli {

double parse_bytes(const std::string& text) {
  const char* begin = text.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin || !std::isfinite(value) || value <= 0) return 0;
  std::string unit(end);
  for (char& c : unit) c = char(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() >= 2 && unit.substr(unit.size() - 2) == "IB") unit.resize(unit.size() - 2);
  else if (!unit.empty() && unit.back() == 'B') unit.pop_back();
  double scale;
  if (unit.empty()) scale = 1;
  else if (unit == "K") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  else return 0;
  return value * scale;
}

std::string size_problem(const std::string& text) {
  return parse_bytes(text) > 0 ? "" : "expected a size such as 256M or 4G";
}

}  // namespace scan2lod::cli
