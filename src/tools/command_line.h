// Reading the tools' command lines, and writing a stamp for them to print.
#pragma once

#include <string>

#include "attitude_propagator/source_timeline.h"

namespace attitude_propagator {
namespace tools {

/// A stamp as seconds with nanosecond digits ("1700000000.005000000"), exact.
std::string formatStamp(Stamp stamp);

/// Command-line reading: the value after option `argv[i]`, or UsageError (none, or empty).
std::string optionValue(int argc, char** argv, int& i);
/// A finite number with nothing after it, or UsageError.
double parseNumber(const std::string& option, const std::string& text);
/// A finite number with |x| <= limit, or UsageError naming the limit and `why`.
double parseNumber(const std::string& option, const std::string& text, double limit,
                   const char* why);

}  // namespace tools
}  // namespace attitude_propagator
