#include "command_line.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>

#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

std::string formatStamp(Stamp stamp) {
  const bool negative = stamp < 0;
  const std::uint64_t magnitude =
      negative ? static_cast<std::uint64_t>(-(stamp + 1)) + 1 : static_cast<std::uint64_t>(stamp);
  char text[40];
  std::snprintf(text, sizeof text, "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000u),
                static_cast<unsigned long long>(magnitude % 1000000000u));
  return text;
}

SplitArguments::SplitArguments(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) {
    const std::string word = argv[i];
    const std::size_t equals = word.find('=');
    if (i > 0 && word.rfind("--", 0) == 0 && equals != std::string::npos && equals > 2) {
      words_.push_back(word.substr(0, equals));  // --output=y.bag: --output y.bag
      words_.push_back(word.substr(equals + 1));
    } else {
      words_.push_back(word);
    }
  }
  for (std::string& w : words_) pointers_.push_back(&w[0]);
}

std::string optionValue(int argc, char** argv, int& i) {
  if (i + 1 >= argc) throw UsageError(std::string(argv[i]) + ": needs a value");
  // An empty value would silently mean the default (an output name, a topic).
  if (argv[i + 1][0] == '\0') throw UsageError(std::string(argv[i]) + ": an empty value");
  return argv[++i];
}

double parseNumber(const std::string& option, const std::string& text) {
  try {
    std::size_t used = 0;
    const double x = std::stod(text, &used);
    if (used == text.size() && std::isfinite(x)) return x;
  } catch (const std::exception&) {
  }
  throw UsageError(option + ": '" + text + "' is not a finite number");
}

double parseNumber(const std::string& option, const std::string& text, double limit,
                   const char* why) {
  const double x = parseNumber(option, text);
  if (std::abs(x) > limit) {
    char bound[32];
    std::snprintf(bound, sizeof bound, "%.10g", limit);
    throw UsageError(option + ": " + text + " is beyond +-" + bound + " (" + why + ")");
  }
  return x;
}

}  // namespace tools
}  // namespace attitude_propagator
