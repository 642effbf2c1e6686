#include "tool_error.h"

#include <cstdio>
#include <new>

namespace attitude_propagator {
namespace tools {

int runTool(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const ToolError& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return e.exit_code;
  } catch (const std::invalid_argument& e) {
    // The parameters' loader and validator refuse a value this way.
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return kExitUsage;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "%s: out of memory\n", name);
    return kExitFailed;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return kExitFailed;
  } catch (...) {
    std::fprintf(stderr, "%s: unexpected error\n", name);
    return kExitFailed;
  }
}

}  // namespace tools
}  // namespace attitude_propagator
