// Reading the tools' command lines (one option table per tool, one parser and one help layout
// for both), and writing a stamp for them to print.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {
namespace tools {

/// A stamp as seconds with nanosecond digits ("1700000000.005000000"), exact.
std::string formatStamp(Stamp stamp);

/// One row of a tool's option table: an option, or a paragraph of its help.
struct Option {
  /// Its spellings as --help shows them, ", " between them ("-o, --output"); empty: the row is
  /// a paragraph of the help, `help` printed as it is.
  std::string names;
  /// The names of its values as --help shows them, one word per value ("OUT.bag", "P C",
  /// "none|lz4"): the word count is how many values it takes; empty: a flag.
  std::string values;
  /// What --help says of it, '\n' between lines (each indented to the help column).
  std::string help;
  /// Given the values (none for a flag); throws UsageError for a value it refuses.
  std::function<void(const std::vector<std::string>&)> take;
};

/// A flag: no value.
Option flagOption(std::string names, std::string help, std::function<void()> take);
/// An option with one value, named `value` in the help.
Option valueOption(std::string names, std::string value, std::string help,
                   std::function<void(const std::string&)> take);
/// An option with one value per word of `values`.
Option valuesOption(std::string names, std::string values, std::string help,
                    std::function<void(const std::vector<std::string>&)> take);
/// A paragraph of the help between options, printed as it is.
Option helpParagraph(std::string text);
/// The rows of -h, --help and --version, which parseCommandLine answers for every tool: the
/// rows only place them in the help.
Option helpOption(std::string help);
Option versionOption(std::string help);

/// A tool's command line: its options, its help around them, and its --version line.
struct CommandLine {
  /// The whole line --version prints ("propagate_bag (attitude_propagator) 1.2.3").
  std::string version;
  /// Width of the option column of the help: help text starts 2 + width + 1 characters in; a
  /// longer option stands on a line of its own.
  std::size_t option_width = 22;
  std::vector<Option> rows;
};

/// The help text: every row in order, options in two columns.
std::string helpText(const CommandLine& line);

/// Reads `argv` by the table, left to right, as rosbag takes options: `--key value` and
/// `--key=value` alike (`-o value` for a short spelling), each option's values from the words
/// after it; -h and --help print the help, --version the version line, and exit 0. Every other
/// word is returned in order (the inputs). An unknown option, a missing or empty value is a
/// UsageError naming the option.
std::vector<std::string> parseCommandLine(const CommandLine& line, int argc, char** argv);

/// A finite number with nothing after it, or UsageError.
double parseNumber(const std::string& option, const std::string& text);
/// A finite number with |x| <= limit, or UsageError naming the limit and `why`.
double parseNumber(const std::string& option, const std::string& text, double limit,
                   const char* why);

}  // namespace tools
}  // namespace attitude_propagator
