#include "attitude_propagator/ros/parameter_loader.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/console.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "attitude_propagator/messages/frame_ids.h"

namespace attitude_propagator {

namespace {

// Private parameters that are not ours to read but are not unknown either: read by libraries
// the node uses (diagnostic_updater reads ~diagnostic_period), or written by the node itself
// (a respawned node finds what its previous run wrote).
const std::vector<std::string> kForeignParameters{"diagnostic_period", "resolved_model",
                                                  "resolved_integrator"};

std::string describe(XmlRpc::XmlRpcValue& value) {
  std::ostringstream text;
  value.write(text);
  return text.str();
}

[[noreturn]] void wrongType(const std::string& name, XmlRpc::XmlRpcValue& value,
                            const std::string& accepted) {
  throw std::invalid_argument(name + ": wrong type, got '" + describe(value) +
                              "'; accepted: " + accepted);
}

/// How to write the decimal number `text` so that YAML 1.1 (PyYAML, hence rosparam and
/// roslaunch) reads a number: with an exponent it needs a dot in the mantissa and a sign in
/// the exponent ("1e12" and "1.0e12" are strings to it, "1.0e+12" is a number); without one
/// the text was quoted. Empty when `text` is not a finite decimal number.
std::string yamlNumberFix(const std::string& text) {
  if (text.empty() || text.find_first_not_of("0123456789+-.eE") != std::string::npos) return "";
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(value)) return "";
  const auto e = text.find_first_of("eE");
  if (e == std::string::npos) return text + " without quotes";
  std::string mantissa = text.substr(0, e);
  std::string exponent = text.substr(e + 1);
  if (mantissa.find('.') == std::string::npos) mantissa += ".0";
  if (exponent[0] != '+' && exponent[0] != '-') exponent = "+" + exponent;
  const std::string fix = mantissa + text[e] + exponent;
  return fix == text ? text + " without quotes" : fix;
}

/// A number that YAML read as a string (`inertia: [1.0e12, ...]` in a file): the error names
/// the text and how to write it, since "wrong type" alone sends one looking elsewhere.
[[noreturn]] void numberAsString(const std::string& name, const std::string& text,
                                 const std::string& fix, const std::string& accepted) {
  throw std::invalid_argument(name + ": '" + text + "' is a string to YAML; write " + fix +
                              " (YAML 1.1 reads an exponent only after a dot and with a sign: "
                              "1.0e+12, 2.5e-3); accepted: " +
                              accepted);
}

/// Throws numberAsString when v is a string that reads as a finite number.
void rejectNumberText(const std::string& name, XmlRpc::XmlRpcValue& v,
                      const std::string& accepted) {
  if (v.getType() != XmlRpc::XmlRpcValue::TypeString) return;
  const std::string text = static_cast<std::string>(v);
  const std::string fix = yamlNumberFix(text);
  if (!fix.empty()) numberAsString(name, text, fix, accepted);
}

bool isNumber(const XmlRpc::XmlRpcValue& v) {
  return v.getType() == XmlRpc::XmlRpcValue::TypeDouble ||
         v.getType() == XmlRpc::XmlRpcValue::TypeInt;
}

double toDouble(XmlRpc::XmlRpcValue& v) {
  return v.getType() == XmlRpc::XmlRpcValue::TypeInt ? static_cast<int>(v) : static_cast<double>(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, std::string& out) {
  if (v.getType() != XmlRpc::XmlRpcValue::TypeString) wrongType(name, v, "a string");
  out = static_cast<std::string>(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, bool& out) {
  if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) wrongType(name, v, "true or false");
  out = static_cast<bool>(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, double& out) {
  rejectNumberText(name, v, "a number");
  if (!isNumber(v)) wrongType(name, v, "a number");
  out = toDouble(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, int& out) {
  rejectNumberText(name, v, "an integer");
  if (v.getType() != XmlRpc::XmlRpcValue::TypeInt) wrongType(name, v, "an integer");
  out = static_cast<int>(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, std::vector<double>& out) {
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray) wrongType(name, v, "a list of numbers");
  out.clear();
  for (int i = 0; i < v.size(); ++i) {
    rejectNumberText(name, v[i], "a list of numbers");
    if (!isNumber(v[i])) wrongType(name, v, "a list of numbers");
    out.push_back(toDouble(v[i]));
  }
}

/// Every private parameter set on the server must be one we know (docs/design.md §7.7): a typo
/// would otherwise silently leave a default in place.
void rejectUnknownNames(const ros::NodeHandle& pnh) {
  std::vector<std::string> keys;
  if (!pnh.getParamNames(keys)) return;  // no master answer: nothing to check against
  const std::string prefix = pnh.getNamespace() + "/";
  const std::vector<std::string> known = parameterNames();
  for (const std::string& key : keys) {
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string name =
        key.substr(prefix.size(), key.find('/', prefix.size()) - prefix.size());
    const bool ok = std::find(known.begin(), known.end(), name) != known.end() ||
                    std::find(kForeignParameters.begin(), kForeignParameters.end(), name) !=
                        kForeignParameters.end();
    if (!ok) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : " ") + k;
      throw std::invalid_argument(name + ": unknown parameter (" + key + "); accepted: " + list);
    }
  }
}

}  // namespace

NodeConfig loadParameters(const ros::NodeHandle& pnh, const std::string& log_prefix) {
  rejectUnknownNames(pnh);
  Parameters parameters;
  forEachParameter(parameters, [&pnh](const char* name, auto& field, const char*, const char*) {
    XmlRpc::XmlRpcValue value;
    if (pnh.getParam(name, value)) read(name, value, field);
  });
  // tf1's leading '/' in a frame parameter is read without it (frame_ids.h), with a warning.
  for (const auto& w : tf2FrameParameters(parameters)) {
    ROS_WARN("%s%s", log_prefix.c_str(), w.c_str());
  }
  NodeConfig config = validateParameters(parameters);
  // Every parameter in use, defaults included, on the server: `rosparam get` shows what runs.
  forEachParameter(config.parameters, [&pnh](const char* name, const auto& field, const char*,
                                             const char*) { pnh.setParam(name, field); });
  return config;
}

}  // namespace attitude_propagator
