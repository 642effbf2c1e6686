// The tools' exit codes, their two errors (one clear line each) and main()'s wrapper that turns
// every exception into that line and its exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace attitude_propagator {
namespace tools {

/// The tools' exit codes (their --help and docs/bag_tools.md list them). A signal that stops a run
/// exits with 128 + its number, as a shell reports a process the signal killed (130: Ctrl-C).
enum ExitCode : int {
  kExitOk = 0,             ///< the inputs were used and every output is complete
  kExitFailed = 1,         ///< an input could not be read (missing, damaged) or an output written
  kExitUsage = 2,          ///< bad options or parameters, an output that is an input
  kExitNothingUsable = 3,  ///< the run completed but produced nothing usable (says why)
  /// evaluate_bag: the truth cannot be one (no orientation, non-unit quaternions, a turn the
  /// rates do not make); nothing written
  kExitTruthRefused = 4,
  /// evaluate_bag: the outputs are complete, but --truth-clock same was contradicted by the
  /// data and the truth compared as on a clock of its own
  kExitClockContradicted = 5,
};

/// One clear line for the user; the tools print it and exit with `code`.
struct ToolError : std::runtime_error {
  explicit ToolError(const std::string& what, int code = kExitFailed)
      : std::runtime_error(what), exit_code(code) {}
  int exit_code;
};

/// A command line the tool cannot run: exit code 2.
struct UsageError : ToolError {
  explicit UsageError(const std::string& what) : ToolError(what, kExitUsage) {}
};

/// main() of a tool: runs `run`, and turns every exception into one line "name: what" on
/// stderr and its exit code (std::invalid_argument, the parameters' refusal, is a usage error).
int runTool(const char* name, int (*run)(int, char**), int argc, char** argv);

}  // namespace tools
}  // namespace attitude_propagator
