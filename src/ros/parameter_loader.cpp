#include "attitude_propagator/ros/parameter_loader.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>

namespace attitude_propagator {

namespace {

// Private parameters read by libraries the node uses, not by us (diagnostic_updater reads
// ~diagnostic_period), so they are not unknown.
const std::vector<std::string> kForeignParameters{"diagnostic_period"};

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
  if (!isNumber(v)) wrongType(name, v, "a number");
  out = toDouble(v);
}

void read(const std::string& name, XmlRpc::XmlRpcValue& v, std::vector<double>& out) {
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray) wrongType(name, v, "a list of numbers");
  out.clear();
  for (int i = 0; i < v.size(); ++i) {
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

NodeConfig loadParameters(const ros::NodeHandle& pnh) {
  rejectUnknownNames(pnh);
  Parameters parameters;
  forEachParameter(parameters, [&pnh](const char* name, auto& field, const char*, const char*) {
    XmlRpc::XmlRpcValue value;
    if (pnh.getParam(name, value)) read(name, value, field);
  });
  NodeConfig config = validateParameters(parameters);
  // Every parameter in use, defaults included, on the server: `rosparam get` shows what runs.
  forEachParameter(config.parameters, [&pnh](const char* name, const auto& field, const char*,
                                             const char*) { pnh.setParam(name, field); });
  return config;
}

}  // namespace attitude_propagator
