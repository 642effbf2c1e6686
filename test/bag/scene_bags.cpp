#include "scene_bags.h"

#include <dirent.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "../core/sampling.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/numerics/rigid_body.h"
#include "attitude_propagator/numerics/torque_free_motion.h"

namespace ap = attitude_propagator;

namespace bagtest {

ros::Time rosTime(Stamp stamp) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(stamp));
  return t;
}

std::vector<Recorded> readRecorded(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<Recorded> all;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    Recorded r{m.getTopic(), m.getTime(), std::vector<std::uint8_t>(m.size())};
    ros::serialization::OStream out(r.bytes.data(), m.size());
    m.write(out);
    all.push_back(std::move(r));
  }
  return all;
}

OutputBag readOutputBag(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  OutputBag out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    ++out.count[m.getTopic()];
    if (auto s = m.instantiate<attitude_propagator::AttitudeState>()) out.states.push_back(*s);
    if (auto i = m.instantiate<sensor_msgs::Imu>()) out.imu.push_back(*i);
    if (m.getTopic() != "/tf") continue;
    if (auto t = m.instantiate<tf2_msgs::TFMessage>()) {
      out.tf.insert(out.tf.end(), t->transforms.begin(), t->transforms.end());
    }
  }
  return out;
}

namespace {

void toMsg(const Eigen::Quaterniond& q, geometry_msgs::Quaternion& m) {
  m.x = q.x(), m.y = q.y(), m.z = q.z(), m.w = q.w();
}

void toMsg(const Eigen::Vector3d& v, geometry_msgs::Vector3& m) {
  m.x = v.x(), m.y = v.y(), m.z = v.z();
}

void writeRate(rosbag::Bag& bag, const SceneBag& s, Stamp stamp, const Eigen::Vector3d& w) {
  const ros::Time t = rosTime(stamp);
  if (s.rate_type == RateType::Imu) {
    sensor_msgs::Imu m;
    m.header.stamp = t;
    m.header.frame_id = s.rate_frame;
    toMsg(w, m.angular_velocity);
    m.orientation_covariance[0] = -1.0;  // REP-145: no orientation in a raw IMU message
    bag.write(s.rate_topic, t, m);
  } else {
    geometry_msgs::TwistStamped m;
    m.header.stamp = t;
    m.header.frame_id = s.rate_frame;
    toMsg(w, m.twist.angular);
    bag.write(s.rate_topic, t, m);
  }
}

void writeTruth(rosbag::Bag& bag, const SceneBag& s, Stamp stamp, const Eigen::Quaterniond& q) {
  const ros::Time t = rosTime(stamp);
  geometry_msgs::TransformStamped transform;
  transform.header.stamp = t;
  transform.header.frame_id = "map";
  transform.child_frame_id = "body_truth";
  toMsg(q, transform.transform.rotation);
  switch (s.truth) {
    case TruthType::None:
      return;
    case TruthType::Pose: {
      geometry_msgs::PoseStamped m;
      m.header = transform.header;
      m.pose.orientation = transform.transform.rotation;
      return bag.write(s.truth_topic, t, m);
    }
    case TruthType::PoseWithCovariance: {
      geometry_msgs::PoseWithCovarianceStamped m;
      m.header = transform.header;
      m.pose.pose.orientation = transform.transform.rotation;
      return bag.write(s.truth_topic, t, m);
    }
    case TruthType::Transform:
      return bag.write(s.truth_topic, t, transform);
    case TruthType::Odometry: {
      nav_msgs::Odometry m;
      m.header = transform.header;
      m.child_frame_id = transform.child_frame_id;
      m.pose.pose.orientation = transform.transform.rotation;
      return bag.write(s.truth_topic, t, m);
    }
    case TruthType::Imu: {
      sensor_msgs::Imu m;
      m.header = transform.header;
      m.orientation = transform.transform.rotation;
      m.orientation_covariance[0] = s.truth_orientation_covariance;
      return bag.write(s.truth_topic, t, m);
    }
    case TruthType::Tf: {
      tf2_msgs::TFMessage m;
      geometry_msgs::TransformStamped other = transform;  // another pair in the same message
      other.child_frame_id = "elsewhere";
      m.transforms = {other, transform};
      return bag.write(s.truth_topic, t, m);
    }
  }
}

/// A second-order Butterworth low-pass at fc = fraction * fs, by the bilinear transform with
/// the cut-off prewarped: b = K^2 (1, 2, 1) / D, a = (1, 2 (K^2 - 1) / D, (1 - sqrt2 K + K^2) /
/// D), K = tan(pi fraction), D = 1 + sqrt2 K + K^2; one state per axis (direct form I).
class Butterworth2 {
 public:
  Butterworth2(double fraction, const Eigen::Vector3d& steady) {
    const double K = std::tan(M_PI * fraction);
    const double D = 1.0 + M_SQRT2 * K + K * K;
    b_ = {K * K / D, 2.0 * K * K / D, K * K / D};
    a_ = {1.0, 2.0 * (K * K - 1.0) / D, (1.0 - M_SQRT2 * K + K * K) / D};
    x1_ = x2_ = y1_ = y2_ = steady;
  }
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) {
    const Eigen::Vector3d y = b_[0] * x + b_[1] * x1_ + b_[2] * x2_ - a_[1] * y1_ - a_[2] * y2_;
    x2_ = x1_, x1_ = x, y2_ = y1_, y1_ = y;
    return y;
  }

 private:
  std::array<double, 3> b_, a_;
  Eigen::Vector3d x1_, x2_, y1_, y2_;
};

}  // namespace

double butterworthDelay(double fraction) { return M_SQRT2 / (2.0 * std::tan(M_PI * fraction)); }

Stamp stampAt(double t) { return kStart + static_cast<Stamp>(std::llround(t * 1e9)); }
geometry_msgs::TransformStamped mountTransform(const std::string& parent, const std::string& child,
                                               const Eigen::Quaterniond& q_PC, Stamp stamp) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = rosTime(stamp);
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.rotation.x = q_PC.x();
  t.transform.rotation.y = q_PC.y();
  t.transform.rotation.z = q_PC.z();
  t.transform.rotation.w = q_PC.w();
  return t;
}

double secondsOf(Stamp stamp) { return static_cast<double>(stamp - kStart) * 1e-9; }

Motion coning(double beta, double omega) {
  const ap::ConingMotion cone{beta, omega};
  return {[cone](double t) { return cone.attitude(t); },
          [cone](double t) { return cone.bodyRate(t); }};
}

Motion tumbling() {
  const auto body = ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d(1.0, 2.0, 3.0));
  const auto motion = std::make_shared<ap::TorqueFreeMotion>(
      body, ap::DynamicState{Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 0.5, 0.8)});
  return {[motion](double t) { return motion->evaluate(t).q_WB; },
          [motion](double t) { return motion->evaluate(t).w_B; }};
}

Motion torquedFromRest(const Eigen::Vector3d& n, double torque, double inertia) {
  const double a = torque / inertia;  // angular acceleration
  return {[n, a](double t) { return ap::expMap(0.5 * a * t * t * n); },
          [n, a](double t) { return Eigen::Vector3d(a * t * n); }};
}

Written writeSceneBag(const std::string& path, const SceneBag& s) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(s.compression == Compression::Bz2   ? rosbag::compression::BZ2
                     : s.compression == Compression::Lz4 ? rosbag::compression::LZ4
                                                         : rosbag::compression::Uncompressed);
  Written out;
  std::uint64_t random = s.seed;
  std::uint64_t truth_random = s.seed + 1;  // apart, so that the rates stay those without noise
  const double h = 1.0 / s.rate_hz;
  const long n = std::lround(s.duration * s.rate_hz);
  const double dt_truth = 1.0 / s.truth_hz;
  long next_truth = 0;
  // The rate a sample carries: at (or over the period up to) rate_delay before its stamp.
  auto sampled = [&s, h](double t) {
    const double at = t - s.rate_delay;
    return s.averaged ? intervalMean(s.motion.rate, at - h, at)
                      : Eigen::Vector3d(s.motion.rate(at));
  };
  const long preroll = std::lround(2.0 * s.rate_hz);
  std::unique_ptr<Butterworth2> lowpass;
  if (s.lowpass > 0.0) {
    lowpass = std::make_unique<Butterworth2>(s.lowpass, sampled(-preroll * h));
    for (long k = -preroll; k < 0; ++k) (*lowpass)(sampled(k * h));
  }
  for (long k = 0; k <= n; ++k) {
    const double t = k * h;
    // Truth samples up to this instant, in stamp order with the rates.
    for (; next_truth * dt_truth <= t + 1e-12; ++next_truth) {
      const double tt = next_truth * dt_truth;
      const double stamped = tt + s.truth_offset;
      if (stamped > s.gap_from && stamped < s.gap_to) continue;
      const Stamp stamp = stampAt(stamped);
      Eigen::Quaterniond q =
          s.fixed * (s.truth_attitude ? s.truth_attitude(tt) : s.motion.attitude(tt)) * s.mount;
      if (s.truth_noise > 0.0) {
        const Eigen::Vector3d n(normalRandom(truth_random), normalRandom(truth_random),
                                normalRandom(truth_random));
        q = q * ap::expMap(s.truth_noise * n);
      }
      q.coeffs() *= s.truth_norm;
      writeTruth(bag, s, stamp, q);
      if (s.truth != TruthType::None) out.truth_stamps.push_back(stamp);
    }
    Eigen::Vector3d w = (lowpass ? (*lowpass)(sampled(t)) : sampled(t)) + s.bias;
    if (std::find(s.non_finite.begin(), s.non_finite.end(), k) != s.non_finite.end()) {
      w.y() = std::nan("");
    }
    const double delay = k > 0 && s.jitter > 0.0 ? s.jitter * normalRandom(random) : 0.0;
    const bool lost = (k > 3 && s.drop > 0.0 && uniformRandom(random) < s.drop) ||
                      std::find(s.lost.begin(), s.lost.end(), k) != s.lost.end();
    if (lost) continue;
    const Stamp stamp = stampAt(t + delay);
    writeRate(bag, s, stamp, w);
    out.rate_stamps.push_back(stamp);
    out.rate_times.push_back(t);
  }
  bag.close();
  return out;
}

void writeTorqueBag(const std::string& path, const Eigen::Vector3d& torque, double hz,
                    double duration, double clock_hz, const std::string& frame) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const long n = std::lround(duration * hz);
  const double dt_clock = clock_hz > 0.0 ? 1.0 / clock_hz : 0.0;
  long next_clock = 0;
  for (long k = 0; k <= n; ++k) {
    const double t = k / hz;
    for (; clock_hz > 0.0 && next_clock * dt_clock <= t + 1e-12; ++next_clock) {
      rosgraph_msgs::Clock c;
      c.clock = rosTime(stampAt(next_clock * dt_clock));
      bag.write("/clock", c.clock, c);
    }
    geometry_msgs::WrenchStamped m;
    m.header.stamp = rosTime(stampAt(t));
    m.header.frame_id = frame;
    toMsg(torque, m.wrench.torque);
    bag.write("/torque", m.header.stamp, m);
  }
  bag.close();
}

std::vector<ChunkData> chunkData(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto u32 = [&bytes](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  std::vector<ChunkData> chunks;
  // "#ROSBAG V2.0\n", then records: header length, header ("<len>op=<byte>" among its
  // fields), data length, data. The index section at the end holds no chunk records.
  std::size_t at = 13;
  while (at + 8 <= bytes.size()) {
    const std::uint32_t header = u32(at);
    const std::string fields = bytes.substr(at + 4, header);
    const std::uint32_t data = u32(at + 4 + header);
    const std::size_t op = fields.find(std::string("op=") + char(0x05));
    if (op != std::string::npos) chunks.push_back({at + 4 + header + 4, data});
    at += 4 + header + 4 + data;
  }
  return chunks;
}

RunResult run(const std::string& command) {
  RunResult r;
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw std::runtime_error("popen failed: " + command);
  char buffer[4096];
  std::size_t got;
  while ((got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0) r.output.append(buffer, got);
  const int status = ::pclose(pipe);
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string quote(const std::string& text) {
  std::string q = "'";
  for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string setQuaternion(const char* name, const Eigen::Quaterniond& q) {
  char text[200];
  std::snprintf(text, sizeof text, "%s=[%.17g, %.17g, %.17g, %.17g]", name, q.x(), q.y(), q.z(),
                q.w());
  return " --set " + quote(text);
}

Eigen::Quaterniond toEigen(const geometry_msgs::Quaternion& q) {
  return Eigen::Quaterniond(q.w, q.x, q.y, q.z);
}

TempDir::TempDir() {
  char pattern[] = "/tmp/bag_tools_test.XXXXXX";
  if (!::mkdtemp(pattern)) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  if (std::getenv("BAG_TESTS_KEEP")) return;
  std::system(("rm -rf " + quote(path_)).c_str());
}

std::vector<std::string> TempDir::list() const {
  std::vector<std::string> names;
  if (DIR* dir = ::opendir(path_.c_str())) {
    while (const dirent* e = ::readdir(dir)) {
      const std::string name = e->d_name;
      if (name != "." && name != "..") names.push_back(name);
    }
    ::closedir(dir);
  }
  return names;
}

bool noPartialFiles(const TempDir& dir) {
  for (const auto& name : dir.list()) {
    if (name.find(".partial") != std::string::npos) return false;
  }
  return true;
}

std::string fileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::vector<std::pair<std::string, std::string>>> readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    return cells;
  };
  std::string line;
  std::getline(in, line);
  const auto header = split(line);
  std::vector<std::vector<std::pair<std::string, std::string>>> rows;
  while (std::getline(in, line)) {
    const auto cells = split(line);
    std::vector<std::pair<std::string, std::string>> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i)
      row.emplace_back(header[i], cells[i]);
    rows.push_back(row);
  }
  return rows;
}

std::string field(const std::vector<std::pair<std::string, std::string>>& row,
                  const std::string& column) {
  for (const auto& [name, value] : row) {
    if (name == column) return value;
  }
  throw std::runtime_error("no column " + column);
}

}  // namespace bagtest
