#include "config_file.h"

#include <stdexcept>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace attitude_propagator {
namespace tools {

namespace {

std::string describe(const YAML::Node& value) {
  YAML::Emitter out;
  out << YAML::Flow << value;
  return out.c_str();
}

[[noreturn]] void wrongType(const std::string& name, const YAML::Node& value,
                            const std::string& accepted) {
  throw std::invalid_argument(name + ": wrong type, got '" + describe(value) +
                              "'; accepted: " + accepted);
}

void read(const std::string& name, const YAML::Node& v, std::string& out) {
  if (!v.IsScalar()) wrongType(name, v, "a string");
  out = v.Scalar();
}

void read(const std::string& name, const YAML::Node& v, bool& out) {
  if (!v.IsScalar()) wrongType(name, v, "true or false");
  try {
    out = v.as<bool>();
  } catch (const YAML::Exception&) {
    wrongType(name, v, "true or false");
  }
}

double number(const std::string& name, const YAML::Node& v, const char* accepted) {
  if (!v.IsScalar()) wrongType(name, v, accepted);
  try {
    return v.as<double>();
  } catch (const YAML::Exception&) {
    wrongType(name, v, accepted);
  }
}

void read(const std::string& name, const YAML::Node& v, double& out) {
  out = number(name, v, "a number");
}

void read(const std::string& name, const YAML::Node& v, int& out) {
  if (!v.IsScalar()) wrongType(name, v, "an integer");
  try {
    out = v.as<int>();
  } catch (const YAML::Exception&) {
    wrongType(name, v, "an integer");
  }
}

void read(const std::string& name, const YAML::Node& v, std::vector<double>& out) {
  if (!v.IsSequence()) wrongType(name, v, "a list of numbers");
  out.clear();
  for (const YAML::Node& x : v) out.push_back(number(name, x, "a list of numbers"));
}

void setParameter(Parameters& p, const std::string& name, const YAML::Node& value) {
  bool known = false;
  forEachParameter(p, [&](const char* n, auto& field, const char*, const char*) {
    if (name != n) return;
    read(name, value, field);
    known = true;
  });
  if (!known) {
    std::string list;
    for (const auto& k : parameterNames()) list += (list.empty() ? "" : " ") + k;
    throw std::invalid_argument(name + ": unknown parameter; accepted: " + list);
  }
}

}  // namespace

void loadConfigFile(const std::string& path, Parameters& p) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::invalid_argument("--config " + path + ": cannot open the file");
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("--config " + path + ": not YAML (" + e.what() + ")");
  } catch (const std::exception& e) {
    // The stream's own errors, e.g. a directory opens but cannot be read.
    throw std::invalid_argument("--config " + path + ": cannot read the file (" + e.what() + ")");
  }
  if (root.IsNull()) return;  // an empty file sets nothing
  if (!root.IsMap()) {
    throw std::invalid_argument("--config " + path + ": expected a map of parameter: value");
  }
  for (const auto& entry : root) setParameter(p, entry.first.Scalar(), entry.second);
}

void applySetting(const std::string& assignment, Parameters& p) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw std::invalid_argument("--set " + assignment + ": expected name=value");
  }
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument("--set " + assignment + ": value is not YAML (" + e.what() + ")");
  }
  setParameter(p, assignment.substr(0, eq), value);
}

}  // namespace tools
}  // namespace attitude_propagator
