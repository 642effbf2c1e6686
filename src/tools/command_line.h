// Reading the tools' command lines, and writing a stamp for them to print.
#pragma once

#include <string>
#include <vector>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {
namespace tools {

/// A stamp as seconds with nanosecond digits ("1700000000.005000000"), exact.
std::string formatStamp(Stamp stamp);

/// The command line with each `--key=value` split into `--key value`, as rosbag and most
/// command lines take both; `argv[0]` and every other word as given. argv() stays valid while
/// this object lives.
class SplitArguments {
 public:
  SplitArguments(int argc, char** argv);
  int argc() const { return static_cast<int>(pointers_.size()); }
  char** argv() { return pointers_.data(); }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
};

/// Command-line reading: the value after option `argv[i]`, or UsageError (none, or empty).
std::string optionValue(int argc, char** argv, int& i);
/// A finite number with nothing after it, or UsageError.
double parseNumber(const std::string& option, const std::string& text);
/// A finite number with |x| <= limit, or UsageError naming the limit and `why`.
double parseNumber(const std::string& option, const std::string& text, double limit,
                   const char* why);

}  // namespace tools
}  // namespace attitude_propagator
