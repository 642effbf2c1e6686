#include "tool_support.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace attitude_propagator {
namespace tools {

namespace {

// ---------------------------------------------------------------------------------------------
// YAML into Parameters (the node reads the same files through rosparam)
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------
// Interrupts
// ---------------------------------------------------------------------------------------------

std::atomic<bool> g_interrupted{false};

extern "C" void onSignal(int) { g_interrupted = true; }

std::string withSlash(const std::string& topic) {
  return !topic.empty() && topic[0] == '/' ? topic : "/" + topic;
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

void openBag(rosbag::Bag& bag, const std::string& path) {
  std::ifstream probe(path, std::ios::binary);
  if (!probe) throw ToolError(path + ": cannot open (" + std::strerror(errno) + ")");
  probe.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(probe.tellg());
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw ToolError(path +
                    ": the bag is unindexed (a recording that did not end cleanly); "
                    "`rosbag reindex " +
                    path + "` rebuilds its index");
  } catch (const rosbag::BagException& e) {
    throw ToolError(path + ": not a readable bag, truncated or damaged (" + e.what() + ", " +
                    std::to_string(size) +
                    " bytes); `rosbag reindex` may recover a truncated "
                    "recording");
  }
}

std::string describeTopics(rosbag::Bag& bag) {
  rosbag::View view(bag);
  std::set<std::string> topics;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    topics.insert(c->topic + " (" + c->datatype + ")");
  }
  std::string text;
  for (const auto& t : topics) text += (text.empty() ? " " : ", ") + t;
  return topics.empty() ? std::string(" no topics") : text;
}

std::optional<std::string> topicType(rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{recordedName(bag, topic)}));
  std::optional<std::string> type;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (type && *type != c->datatype) {
      throw ToolError(topic + ": carries more than one type (" + *type + ", " + c->datatype + ")");
    }
    type = c->datatype;
  }
  return type;
}

std::string recordedName(rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (c->topic == topic) return topic;
  }
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (withSlash(c->topic) == withSlash(topic)) return c->topic;
  }
  return topic;
}

std::string requireTopic(rosbag::Bag& bag, const std::string& topic, const char* role,
                         const std::vector<std::pair<std::string, std::string>>& accepted) {
  std::string names;
  for (const auto& a : accepted) names += (names.empty() ? "" : " or ") + a.first;
  const std::string in = recordedName(bag, topic);
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{in}));
  const auto connections = view.getConnections();
  if (connections.empty()) {
    throw ToolError(bag.getFileName() + ": no " + role + " topic '" + topic + "' (" + names +
                    "); the bag has:" + describeTopics(bag));
  }
  for (const rosbag::ConnectionInfo* c : connections) {
    const bool ok = std::any_of(accepted.begin(), accepted.end(), [c](const auto& a) {
      return a.first == c->datatype && a.second == c->md5sum;
    });
    if (!ok) {
      throw ToolError(bag.getFileName() + ": " + role + " topic '" + in + "' carries " +
                      c->datatype + " (md5 " + c->md5sum + "); accepted: " + names);
    }
  }
  if (view.size() == 0)
    throw ToolError(bag.getFileName() + ": " + role + " topic '" + in + "' has no messages");
  return connections.front()->datatype;
}

// ---------------------------------------------------------------------------------------------
// Progress
// ---------------------------------------------------------------------------------------------

Progress::Progress(std::uint64_t total, bool enabled)
    : total_(total),
      enabled_(enabled && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

double Progress::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::draw(std::uint64_t done, bool force) {
  const auto now = std::chrono::steady_clock::now();
  if (!force && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double t = std::chrono::duration<double>(now - start_).count();
  const double share = total_ > 0 ? std::min(1.0, double(done) / double(total_)) : 1.0;
  const double rate = t > 0.0 ? double(done) / t : 0.0;
  const double left = rate > 0.0 ? double(total_ - std::min(done, total_)) / rate : 0.0;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(share * kWidth);
  std::fprintf(stderr, "\r[%s%s] %3.0f%%  %llu/%llu msgs  %.3g msg/s  ETA %d:%02d ",
               std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(),
               100.0 * share, static_cast<unsigned long long>(done),
               static_cast<unsigned long long>(total_), rate, static_cast<int>(left) / 60,
               static_cast<int>(left) % 60);
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_) return;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

void catchInterrupts() {
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

void throwIfInterrupted() {
  if (g_interrupted) throw ToolError("interrupted: no output written");
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

PendingFile::PendingFile(std::string path) : path_(std::move(path)) {
  const auto slash = path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path_ : path_.substr(slash + 1);
  if (name.empty()) throw ToolError(path_ + ": not a file name");
  temporary_ = dir + "." + name + ".partial-" + std::to_string(::getpid());
}

PendingFile::~PendingFile() {
  if (!committed_) std::remove(temporary_.c_str());
}

void PendingFile::commit() {
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throw ToolError(path_ + ": cannot write (" + std::strerror(errno) + ")");
  }
  committed_ = true;
}

CsvFile::CsvFile(const std::string& path) : path_(path), buffer_(1 << 20) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw ToolError(path + ": cannot write (" + std::strerror(errno) + ")");
  std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
}

CsvFile::~CsvFile() {
  if (file_) std::fclose(file_);
}

void CsvFile::close() {
  const bool failed = std::ferror(file_) != 0;
  const int closed = std::fclose(file_);
  file_ = nullptr;
  if (failed || closed != 0) throw ToolError(path_ + ": write failed (disk full?)");
}

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

std::string optionValue(int argc, char** argv, int& i) {
  if (i + 1 >= argc) throw ToolError(std::string(argv[i]) + ": needs a value");
  return argv[++i];
}

double parseNumber(const std::string& option, const std::string& text) {
  try {
    std::size_t used = 0;
    const double x = std::stod(text, &used);
    if (used == text.size() && std::isfinite(x)) return x;
  } catch (const std::exception&) {
  }
  throw ToolError(option + ": '" + text + "' is not a finite number");
}

}  // namespace tools
}  // namespace attitude_propagator
