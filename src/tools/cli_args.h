// Minimal "--key value" command-line parsing shared by the tools.
#pragma once

#include <cmath>
#include <cstdlib>
#include <map>
#include <string>

namespace go_feap::tools {

/// Parses argv as "--key value" pairs and bare "--flag"s named in `flags`, each at most once. Returns an
/// error message (empty when fine); "-h"/"--help" sets `help`.
inline std::string parseArgs(int argc, char** argv, const std::map<std::string, bool>& known,
                             std::map<std::string, std::string>& values, bool& help) {
  help = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      help = true;
      continue;
    }
    const auto it = known.find(a);
    if (it == known.end()) return "unknown argument '" + a + "'";
    // Given twice, the last would silently win: "--runs 3 ... --runs 5" ran 5.
    if (values.count(a)) return a + " is given twice";
    if (!it->second) {  // a flag without value
      values[a] = "1";
      continue;
    }
    if (i + 1 >= argc) return a + " needs a value";
    values[a] = argv[++i];
  }
  return "";
}

/// Parses a whole non-negative integer; false on anything else.
inline bool parseCount(const std::string& text, unsigned long long& out) {
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) return false;
  try {
    out = std::stoull(text);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

/// Parses a whole finite decimal number (no trailing text, no hex, no inf or nan); false on anything else.
inline bool parseNumber(const std::string& text, double& out) {
  if (text.empty() || text.find_first_not_of("0123456789+-.eE") != std::string::npos) return false;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(value)) return false;
  out = value;
  return true;
}

}  // namespace go_feap::tools
