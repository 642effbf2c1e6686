#include "tool_support.h"

#include <sys/stat.h>
#include <sys/statvfs.h>
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

#include <roslz4/lz4s.h>
#include <yaml-cpp/yaml.h>

#include "bag_check.h"
#include "bag_format.h"

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

// The first signal only sets g_signal: the run stops at its next check and unwinds, which
// removes the partial files. A second one (the user insists, or the run is stuck in a long
// system call) removes them here and exits at once. The handler reads only lock-free atomics
// and fixed arrays and calls only unlink() and _exit(), which are async-signal-safe.
std::atomic<int> g_signal{0};
constexpr int kPendingSlots = 4;
constexpr std::size_t kPendingPath = 4096;
std::atomic<bool> g_pending_used[kPendingSlots];
char g_pending_path[kPendingSlots][kPendingPath];

extern "C" void onSignal(int signal) {
  int none = 0;
  if (g_signal.compare_exchange_strong(none, signal)) return;
  for (int i = 0; i < kPendingSlots; ++i) {
    if (g_pending_used[i].load()) ::unlink(g_pending_path[i]);
  }
  ::_exit(128 + signal);
}

/// Makes `path` known to the signal handler; returns its slot, or -1 when none is free (or the
/// name is too long), and then only the destructor removes it.
int registerPending(const std::string& path) {
  if (path.size() >= kPendingPath) return -1;
  for (int i = 0; i < kPendingSlots; ++i) {
    if (g_pending_used[i].load()) continue;
    std::memcpy(g_pending_path[i], path.c_str(), path.size() + 1);
    g_pending_used[i].store(true);  // after the name is complete
    return i;
  }
  return -1;
}

void unregisterPending(int slot) {
  if (slot >= 0) g_pending_used[slot].store(false);
}

std::string directoryOf(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

/// The absolute path without symlinks, "." or "..": of the file itself when it exists,
/// otherwise of its directory followed by its name.
std::string canonicalPath(const std::string& path) {
  if (char* full = ::realpath(path.c_str(), nullptr)) {
    const std::string text = full;
    std::free(full);
    return text;
  }
  const auto slash = path.rfind('/');
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (char* dir = ::realpath(directoryOf(path).c_str(), nullptr)) {
    const std::string text = std::string(dir) + "/" + name;
    std::free(dir);
    return text;
  }
  return path;
}

std::string megabytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MB", double(bytes) / 1e6);
  return text;
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

void openBag(rosbag::Bag& bag, const std::string& path) {
  struct stat file {};
  if (::stat(path.c_str(), &file) == 0 && S_ISDIR(file.st_mode)) {
    throw ToolError(path + ": is a directory, not a bag");
  }
  std::ifstream probe(path, std::ios::binary);
  if (!probe) {
    const int error = errno;
    // A shell passes a pattern that matches no file on as it is (bash without nullglob).
    const bool pattern = error == ENOENT && path.find_first_of("*?[") != std::string::npos;
    throw ToolError(path + ": cannot open (" + std::strerror(error) + ")" +
                    (pattern ? "; a pattern that matched no file" : ""));
  }
  probe.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(probe.tellg());
  probe.close();
  checkBagStructure(path);
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

namespace {

/// The topic's name as recorded in `bag` ("imu" may be recorded as "/imu").
std::string recordedName(rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (c->topic == topic) return topic;
  }
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (sameTopic(c->topic, topic)) return c->topic;
  }
  return topic;
}

rosbag::TopicQuery queryIn(rosbag::Bag& bag, const std::vector<std::string>& topics) {
  std::vector<std::string> names;
  for (const auto& t : topics) names.push_back(recordedName(bag, t));
  return rosbag::TopicQuery(names);
}

std::string seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", s);
  return text;
}

}  // namespace

BagSet::BagSet(const std::vector<std::string>& paths) : paths_(paths) {
  for (std::size_t i = 0; i < paths.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      struct stat a {};
      struct stat b {};
      const bool same = ::stat(paths[i].c_str(), &a) == 0 && ::stat(paths[j].c_str(), &b) == 0 &&
                        a.st_dev == b.st_dev && a.st_ino == b.st_ino;
      if (same) {
        throw UsageError(paths[i] + ": given twice (the same file as " + paths[j] +
                         "); each input is read once");
      }
    }
  }
  for (const auto& path : paths) {
    bags_.push_back(std::make_unique<rosbag::Bag>());
    openBag(*bags_.back(), path);
  }
}

std::string BagSet::name() const {
  std::string text;
  for (const auto& p : paths_) text += (text.empty() ? "" : ", ") + p;
  return text;
}

void BagSet::addQuery(rosbag::View& view, const std::vector<std::string>& topics) {
  for (auto& bag : bags_) view.addQuery(*bag, queryIn(*bag, topics));
}

std::vector<std::string> BagSet::overlaps(const std::vector<std::string>& topics) {
  struct Span {
    ros::Time begin, end;
    bool any;
  };
  std::vector<Span> spans;
  for (auto& bag : bags_) {
    rosbag::View view(*bag, queryIn(*bag, topics));
    spans.push_back({view.getBeginTime(), view.getEndTime(), view.size() > 0});
  }
  std::vector<std::string> found;
  for (std::size_t i = 0; i < spans.size(); ++i) {
    for (std::size_t j = i + 1; j < spans.size(); ++j) {
      if (!spans[i].any || !spans[j].any) continue;
      const ros::Time from = std::max(spans[i].begin, spans[j].begin);
      const ros::Time to = std::min(spans[i].end, spans[j].end);
      // Split parts touch at most at one record time (a message on each side of the cut).
      if (to > from) {
        found.push_back(paths_[i] + " and " + paths_[j] + " share " + seconds((to - from).toSec()));
      }
    }
  }
  return found;
}

std::string describeTopics(BagSet& bags) {
  std::set<std::string> topics;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      topics.insert(c->topic + " (" + c->datatype + ")");
    }
  }
  std::string text;
  for (const auto& t : topics) text += (text.empty() ? " " : ", ") + t;
  return topics.empty() ? std::string(" no topics") : text;
}

std::optional<std::string> topicType(BagSet& bags, const std::string& topic) {
  std::optional<std::string> type;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i), queryIn(bags.bag(i), {topic}));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      if (type && *type != c->datatype) {
        throw ToolError(topic + ": carries more than one type (" + *type + ", " + c->datatype +
                        ")");
      }
      type = c->datatype;
    }
  }
  return type;
}

std::string requireTopic(BagSet& bags, const std::string& topic, const char* role,
                         const std::vector<std::pair<std::string, std::string>>& accepted) {
  std::string names;
  for (const auto& a : accepted) names += (names.empty() ? "" : " or ") + a.first;
  std::optional<std::string> found;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i), queryIn(bags.bag(i), {topic}));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      const bool ok = std::any_of(accepted.begin(), accepted.end(), [c](const auto& a) {
        return a.first == c->datatype && a.second == c->md5sum;
      });
      if (!ok) {
        throw ToolError(bags.paths()[i] + ": " + role + " topic '" + c->topic + "' carries " +
                        c->datatype + " (md5 " + c->md5sum + "); accepted: " + names);
      }
      found = c->datatype;
    }
  }
  if (!found) {
    throw ToolError(bags.name() + ": no " + role + " topic '" + topic + "' (" + names +
                    "); the bag" + (bags.size() > 1 ? "s have" : " has") + ":" +
                    describeTopics(bags));
  }
  if (messageCount(bags, {topic}) == 0) {
    throw ToolError(bags.name() + ": " + role + " topic '" + topic + "' has no messages");
  }
  return *found;
}

std::uint64_t messageCount(BagSet& bags, const std::vector<std::string>& topics) {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    n += rosbag::View(bags.bag(i), queryIn(bags.bag(i), topics)).size();
  }
  return n;
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
  struct sigaction action {};
  action.sa_handler = onSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  for (int signal : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(signal, &action, nullptr);
  std::signal(SIGXFSZ, SIG_IGN);
}

void throwIfInterrupted() {
  if (const int signal = g_signal.load()) {
    throw ToolError(std::string("interrupted (") + ::strsignal(signal) + "): no output written",
                    128 + signal);
  }
}

void refuseOutputOverInput(const std::string& output, const std::vector<std::string>& inputs) {
  struct stat out {};
  const bool exists = ::stat(output.c_str(), &out) == 0;
  if (exists && S_ISDIR(out.st_mode)) {
    throw UsageError(output + ": is a directory; give the output's file name");
  }
  if (exists && !S_ISREG(out.st_mode)) {
    // The output is written aside and renamed over its name: that would replace a device or a
    // pipe, not write into it.
    throw UsageError(output + ": is not a regular file (a device or a pipe); give a file name");
  }
  for (const std::string& input : inputs) {
    struct stat in {};
    const bool same = exists && ::stat(input.c_str(), &in) == 0
                          ? in.st_dev == out.st_dev && in.st_ino == out.st_ino
                          : canonicalPath(output) == canonicalPath(input);
    if (same) {
      throw UsageError(output + ": is the input " + input +
                       " (the same file); choose another output name");
    }
  }
}

void requireFreeSpace(const std::string& output, std::uint64_t bytes) {
  const std::string dir = directoryOf(output);
  struct statvfs fs {};
  if (::statvfs(dir.c_str(), &fs) != 0) {
    throw ToolError(output + ": cannot write into " + dir + " (" + std::strerror(errno) + ")");
  }
  // f_bavail: the blocks an unprivileged writer may use (root may use a few more).
  const std::uint64_t available = std::uint64_t(fs.f_bavail) * fs.f_frsize;
  if (available < bytes) {
    throw ToolError(output + ": needs about " + megabytes(bytes) + " and its file system has " +
                    megabytes(available) + " free; free some space or write elsewhere");
  }
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

PendingFile::PendingFile(std::string path) : path_(std::move(path)) {
  const auto slash = path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path_ : path_.substr(slash + 1);
  if (name.empty()) throw UsageError(path_ + ": not a file name");
  temporary_ = dir + "." + name + ".partial-" + std::to_string(::getpid());
  slot_ = registerPending(temporary_);
}

PendingFile::~PendingFile() {
  if (!committed_) std::remove(temporary_.c_str());
  unregisterPending(slot_);
}

void PendingFile::commit() {
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throw ToolError(path_ + ": cannot write (" + std::strerror(errno) + ")");
  }
  committed_ = true;
  unregisterPending(slot_);
  slot_ = -1;
}

CsvFile::CsvFile(const std::string& path, const std::string& name) : name_(name), buffer_(1 << 20) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw ToolError(name + ": cannot write (" + std::strerror(errno) + ")");
  std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
}

CsvFile::~CsvFile() {
  if (file_) std::fclose(file_);
}

void CsvFile::fail(int error) {
  throw ToolError(name_ + ": write failed (" + std::strerror(error) + ")");
}

void CsvFile::check() {
  // The error flag is set by the write that failed, when the buffer was flushed; errno still
  // holds its reason (no call since could have failed).
  if (std::ferror(file_)) fail(errno);
}

void CsvFile::close() {
  check();
  const int closed = std::fclose(file_);
  const int error = errno;
  file_ = nullptr;
  if (closed != 0) fail(error);
}

// ---------------------------------------------------------------------------------------------
// Bag output (format 2.0: records of "<header length><header><data length><data>", the header
// a list of "<field length>name=value"; integers little-endian, times as sec then nsec)
// ---------------------------------------------------------------------------------------------

namespace {

using namespace bag_format;  // NOLINT: the format's names are this file's vocabulary
constexpr std::uint32_t kIndexVersion = 1;
constexpr std::size_t kBagHeaderLength = 4096;  // header and padding, as rosbag writes it
constexpr int kLz4BlockSizeId = 6;              // rosbag's

void appendBytes(std::vector<std::uint8_t>& out, const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  out.insert(out.end(), p, p + size);
}

template <class T>
void appendValue(std::vector<std::uint8_t>& out, const T& value) {
  appendBytes(out, &value, sizeof value);  // the format's little-endian is the host's (x86, ARM)
}

void appendTime(std::vector<std::uint8_t>& out, const ros::Time& t) {
  appendValue(out, t.sec);
  appendValue(out, t.nsec);
}

/// A record header under construction.
class Fields {
 public:
  template <class T>
  Fields& add(const char* name, const T& value) {
    return addRaw(name, &value, sizeof value);
  }
  Fields& add(const char* name, const ros::Time& t) {
    std::vector<std::uint8_t> v;
    appendTime(v, t);
    return addRaw(name, v.data(), v.size());
  }
  Fields& add(const char* name, const std::string& value) {
    return addRaw(name, value.data(), value.size());
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  Fields& addRaw(const char* name, const void* value, std::size_t size) {
    const std::size_t n = std::strlen(name);
    appendValue(bytes_, static_cast<std::uint32_t>(n + 1 + size));
    appendBytes(bytes_, name, n);
    bytes_.push_back('=');
    appendBytes(bytes_, value, size);
    return *this;
  }
  std::vector<std::uint8_t> bytes_;
};

void appendRecord(std::vector<std::uint8_t>& out, const Fields& header, const void* data,
                  std::size_t size) {
  appendValue(out, static_cast<std::uint32_t>(header.bytes().size()));
  appendBytes(out, header.bytes().data(), header.bytes().size());
  appendValue(out, static_cast<std::uint32_t>(size));
  appendBytes(out, data, size);
}

/// A connection record: topic and id in the header, the connection header as data.
void appendConnection(std::vector<std::uint8_t>& out, std::uint32_t id, const std::string& topic,
                      const std::string& datatype, const std::string& md5sum,
                      const std::string& definition, bool latched) {
  Fields data;
  data.add("topic", topic).add("type", datatype).add("md5sum", md5sum);
  data.add("message_definition", definition);
  // As `rosbag record` stores a latched publisher's connection header: `rosbag play` then
  // latches the topic, so a node that subscribes later still receives it.
  if (latched)
    data.add("callerid", std::string("/propagate_bag")).add("latching", std::string("1"));
  appendRecord(out, Fields().add("op", Op::kConnection).add("conn", id).add("topic", topic),
               data.bytes().data(), data.bytes().size());
}

}  // namespace

BagOutput::BagOutput(const std::string& path, const std::string& name, Compression compression,
                     std::uint32_t chunk_threshold)
    : name_(name), compression_(compression), threshold_(chunk_threshold) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw ToolError(name + ": cannot write (" + std::strerror(errno) + ")");
  out_.assign(kVersionLine, kVersionLine + kVersionLength);
  put(out_);
  writeHeader(0);  // rewritten by close()
  chunk_.reserve(threshold_ + (64u << 10));
}

BagOutput::~BagOutput() {
  if (file_) std::fclose(file_);
}

std::uint32_t BagOutput::connection(const std::string& topic, const char* datatype,
                                    const char* md5sum, const char* definition) {
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    if (connections_[id].topic == topic) return id;
  }
  const auto id = static_cast<std::uint32_t>(connections_.size());
  connections_.push_back({topic, datatype, md5sum, definition, {}, 0, false});
  // Also inside the chunk where it first appears, as rosbag writes it (`rosbag reindex` needs it);
  // the message that follows opens the chunk.
  connections_.back().latched = latched_.count(topic) > 0;
  appendConnection(chunk_, id, topic, datatype, md5sum, definition, connections_.back().latched);
  return id;
}

std::uint8_t* BagOutput::beginMessage(std::uint32_t id, const ros::Time& time,
                                      std::uint32_t length) {
  if (time < ros::TIME_MIN) {
    throw ToolError(name_ + ": record time " + std::to_string(time.toSec()) +
                    " is before ros::TIME_MIN");
  }
  if (!chunk_open_) {
    chunk_open_ = true;
    chunk_start_ = chunk_end_ = time;
  }
  chunk_start_ = std::min(chunk_start_, time);
  chunk_end_ = std::max(chunk_end_, time);
  Connection& c = connections_[id];
  appendTime(c.index, time);
  appendValue(c.index, static_cast<std::uint32_t>(chunk_.size()));
  ++c.count;
  const Fields header = Fields().add("op", Op::kMessage).add("conn", id).add("time", time);
  appendValue(chunk_, static_cast<std::uint32_t>(header.bytes().size()));
  appendBytes(chunk_, header.bytes().data(), header.bytes().size());
  appendValue(chunk_, length);
  chunk_.resize(chunk_.size() + length);
  return chunk_.data() + chunk_.size() - length;
}

void BagOutput::writeChunk() {
  if (!chunk_open_) return;
  ChunkInfo info{position_, chunk_start_, chunk_end_, {}};
  const auto size = static_cast<std::uint32_t>(chunk_.size());
  const void* data = chunk_.data();
  std::uint32_t stored = size;
  if (compression_ == Compression::Lz4) {
    // The frame roslz4 writes for rosbag; the bound is LZ4's worst case plus the framing.
    compressed_.resize(size + size / 255 + 16 * (size / 65536 + 1) + 64);
    unsigned int n = static_cast<unsigned int>(compressed_.size());
    if (roslz4_buffToBuffCompress(reinterpret_cast<char*>(chunk_.data()), size, compressed_.data(),
                                  &n, kLz4BlockSizeId) != ROSLZ4_OK) {
      throw ToolError(name_ + ": LZ4 compression failed");
    }
    data = compressed_.data();
    stored = n;
  }
  out_.clear();
  appendRecord(
      out_,
      Fields()
          .add("op", Op::kChunk)
          .add("compression", std::string(compression_ == Compression::Lz4 ? "lz4" : "none"))
          .add("size", size),
      data, stored);
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    Connection& c = connections_[id];
    if (c.count == 0) continue;
    appendRecord(out_,
                 Fields()
                     .add("op", Op::kIndex)
                     .add("ver", kIndexVersion)
                     .add("conn", id)
                     .add("count", c.count),
                 c.index.data(), c.index.size());
    info.counts.emplace_back(id, c.count);
    c.index.clear();
    c.count = 0;
  }
  put(out_);
  chunks_.push_back(std::move(info));
  chunk_.clear();
  chunk_open_ = false;
}

void BagOutput::writeHeader(std::uint64_t index_position) {
  const Fields header = Fields()
                            .add("op", Op::kBagHeader)
                            .add("index_pos", index_position)
                            .add("conn_count", static_cast<std::uint32_t>(connections_.size()))
                            .add("chunk_count", static_cast<std::uint32_t>(chunks_.size()));
  // Padded as rosbag pads it (readers such as `rosbag reindex` skip exactly this much).
  const std::size_t padding = kBagHeaderLength - header.bytes().size();
  out_.clear();
  appendRecord(out_, header, std::string(padding, ' ').data(), padding);
  put(out_);
}

void BagOutput::fail(int error) {
  throw ToolError(name_ + ": write failed (" + std::strerror(error) + ")");
}

void BagOutput::put(const std::vector<std::uint8_t>& bytes) {
  // Stops at the first failed write: a full disk ends the run now, not after the whole bag.
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) fail(errno);
  position_ += bytes.size();
}

void BagOutput::close() {
  writeChunk();
  const std::uint64_t index_position = position_;
  out_.clear();
  for (std::uint32_t id = 0; id < connections_.size(); ++id) {
    const Connection& c = connections_[id];
    appendConnection(out_, id, c.topic, c.datatype, c.md5sum, c.definition, c.latched);
  }
  for (const ChunkInfo& info : chunks_) {
    std::vector<std::uint8_t> counts;
    for (const auto& [id, n] : info.counts) {
      appendValue(counts, id);
      appendValue(counts, n);
    }
    appendRecord(out_,
                 Fields()
                     .add("op", Op::kChunkInfo)
                     .add("ver", kIndexVersion)
                     .add("chunk_pos", info.position)
                     .add("start_time", info.start)
                     .add("end_time", info.end)
                     .add("count", static_cast<std::uint32_t>(info.counts.size())),
                 counts.data(), counts.size());
  }
  put(out_);
  if (std::fseek(file_, kVersionLength, SEEK_SET) != 0) fail(errno);
  writeHeader(index_position);
  const int closed = std::fclose(file_);
  const int error = errno;
  file_ = nullptr;
  if (closed != 0) fail(error);
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
  if (i + 1 >= argc) throw UsageError(std::string(argv[i]) + ": needs a value");
  // An empty value would silently mean the default (an output name, a topic).
  if (argv[i + 1][0] == '\0') throw UsageError(std::string(argv[i]) + ": an empty value");
  return argv[++i];
}

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
