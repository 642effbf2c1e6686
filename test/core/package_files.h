// The package's own files, for the tests that hold the docs and the configuration to the code:
// the package root as the build gives it (AP_PACKAGE_ROOT: __FILE__ may be relative to the
// folder the compiler ran in, as the compiler cache makes it), and a file's text.
#pragma once

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace package_files {

inline std::filesystem::path packageRoot() { return std::filesystem::path(AP_PACKAGE_ROOT); }

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace package_files
