#include "command_line.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <utility>

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

// ---------------------------------------------------------------------------------------------
// The option table
// ---------------------------------------------------------------------------------------------

Option flagOption(std::string names, std::string help, std::function<void()> take) {
  return {std::move(names), "", std::move(help),
          [take = std::move(take)](const std::vector<std::string>&) { take(); }};
}

Option valueOption(std::string names, std::string value, std::string help,
                   std::function<void(const std::string&)> take) {
  return {std::move(names), std::move(value), std::move(help),
          [take = std::move(take)](const std::vector<std::string>& v) { take(v.front()); }};
}

Option valuesOption(std::string names, std::string values, std::string help,
                    std::function<void(const std::vector<std::string>&)> take) {
  return {std::move(names), std::move(values), std::move(help), std::move(take)};
}

Option helpParagraph(std::string text) { return {"", "", std::move(text), nullptr}; }

Option helpOption(std::string help) { return {"-h, --help", "", std::move(help), nullptr}; }

Option versionOption(std::string help) { return {"--version", "", std::move(help), nullptr}; }

namespace {

std::vector<std::string> words(const std::string& text, const std::string& separator) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find(separator, start);
    out.push_back(text.substr(start, end - start));
    if (end == std::string::npos) break;
    start = end + separator.size();
  }
  return out;
}

/// `--key=value` as `--key value`, as rosbag and most command lines take both; a short option
/// and every other word as given (a value may hold '=': `--set name=value`).
std::vector<std::string> splitKeyValues(int argc, char** argv) {
  std::vector<std::string> out;
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    const std::size_t equals = word.find('=');
    if (word.rfind("--", 0) == 0 && equals != std::string::npos && equals > 2) {
      out.push_back(word.substr(0, equals));
      out.push_back(word.substr(equals + 1));
    } else {
      out.push_back(word);
    }
  }
  return out;
}

bool spelledAs(const Option& option, const std::string& word) {
  if (option.names.empty()) return false;
  for (const std::string& name : words(option.names, ", ")) {
    if (name == word) return true;
  }
  return false;
}

/// The values of `option` given as `word`, from the words after position `i` (moved past them).
std::vector<std::string> takeValues(const Option& option, const std::string& word,
                                    const std::vector<std::string>& argv, std::size_t& i) {
  const std::size_t n = words(option.values, " ").size();
  std::vector<std::string> values;
  for (std::size_t k = 0; k < n; ++k) {
    if (i + 1 >= argv.size()) {
      throw UsageError(
          word + (n == 1 ? ": needs a value"
                         : ": needs " + std::to_string(n) + " values (" + option.values + ")"));
    }
    // An empty value would silently mean the default (an output name, a topic).
    if (argv[i + 1].empty()) throw UsageError(word + ": an empty value");
    values.push_back(argv[++i]);
  }
  return values;
}

}  // namespace

std::string helpText(const CommandLine& line) {
  const std::string indent(2 + line.option_width + 1, ' ');
  std::string text;
  for (const Option& row : line.rows) {
    if (row.names.empty()) {
      text += row.help;
      continue;
    }
    std::string label = row.names + (row.values.empty() ? "" : " " + row.values);
    const std::vector<std::string> lines = words(row.help, "\n");
    if (label.size() > line.option_width) {
      text += "  " + label + "\n";  // too wide for the column: the help starts below it
    } else {
      label.resize(line.option_width, ' ');
      text += "  " + label + " " + (lines.empty() ? "" : lines.front()) + "\n";
    }
    const std::size_t from = label.size() > line.option_width ? 0 : 1;
    for (std::size_t k = from; k < lines.size(); ++k) text += indent + lines[k] + "\n";
  }
  return text;
}

std::vector<std::string> parseCommandLine(const CommandLine& line, int argc, char** argv) {
  const std::vector<std::string> given = splitKeyValues(argc, argv);
  std::vector<std::string> inputs;
  for (std::size_t i = 0; i < given.size(); ++i) {
    const std::string& word = given[i];
    if (word == "-h" || word == "--help") {
      std::cout << helpText(line);
      std::exit(0);
    }
    if (word == "--version") {
      std::cout << line.version << "\n";
      std::exit(0);
    }
    if (word.empty() || word[0] != '-') {
      inputs.push_back(word);
      continue;
    }
    const Option* option = nullptr;
    for (const Option& row : line.rows) {
      if (row.take && spelledAs(row, word)) option = &row;
    }
    if (!option) throw UsageError(word + ": unknown option (see --help)");
    option->take(takeValues(*option, word, given, i));
  }
  return inputs;
}

// ---------------------------------------------------------------------------------------------
// Values
// ---------------------------------------------------------------------------------------------

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
