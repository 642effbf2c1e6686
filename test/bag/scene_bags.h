// Small bags written from closed-form motions, for the tests of the bag tools: a rate topic as
// a gyro would deliver it (point or interval-averaged samples, receipt jitter, lost samples)
// and a truth attitude topic (any supported type, its own rate, a clock offset, gaps, a
// rotated fixed frame and a mounted sensor), or a torque topic.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/Imu.h>
#include <Eigen/Geometry>

#include "attitude_propagator/AttitudeState.h"

namespace bagtest {

using Stamp = std::int64_t;
/// Physical time 0 of every scene: a stamp near today's epoch, so that the tools meet
/// stamps as real bags have them.
constexpr Stamp kStart = 1700000000LL * 1000000000LL;
Stamp stampAt(double t);         ///< kStart + t seconds, rounded to the nanosecond
ros::Time rosTime(Stamp stamp);  ///< the same instant as a ros::Time
double secondsOf(Stamp stamp);   ///< (stamp - kStart) in seconds

/// A transform parent -> child with the rotation q_PC (no translation), stamped `stamp`: a
/// mount as a /tf_static message carries it.
geometry_msgs::TransformStamped mountTransform(const std::string& parent, const std::string& child,
                                               const Eigen::Quaterniond& q_PC, Stamp stamp);

/// A motion: the sensor's attitude q_WS(t) and the body rate w_S(t) that generates it.
struct Motion {
  std::function<Eigen::Quaterniond(double)> attitude;
  std::function<Eigen::Vector3d(double)> rate;
};
Motion coning(double beta = 0.1, double omega = 2.0 * M_PI * 1.1);
/// Torque-free triaxial body (moments 1, 2, 3, w0 = (1, 0.5, 0.8) rad/s): |w| varies.
Motion tumbling();
/// From rest under a constant torque T about the unit axis n of a principal moment I:
/// w = (T / I) t n, q = Exp(T t^2 / (2 I) n).
Motion torquedFromRest(const Eigen::Vector3d& n, double torque, double inertia);

enum class RateType { Imu, TwistStamped };
enum class Compression { None, Bz2, Lz4 };
enum class TruthType { None, Pose, PoseWithCovariance, Transform, Odometry, Tf, Imu };

struct SceneBag {
  Motion motion;
  double duration = 20.0;  ///< s
  double rate_hz = 200.0;
  bool averaged = false;  ///< each sample the mean rate over the period it closes
  double jitter = 0.0;    ///< s, standard deviation of the receipt delay about its mean
  /// s: each sample is the rate (or mean) of rate_delay before its stamp (a fixed latency)
  double rate_delay = 0.0;
  /// When positive: the samples pass a 2nd-order Butterworth low-pass at lowpass * rate_hz
  /// (an on-chip filter), started in its steady state two seconds before the first sample;
  /// its group delay at DC is butterworthDelay(lowpass) / rate_hz.
  double lowpass = 0.0;
  double drop = 0.0;  ///< probability that a sample is lost (never the first four)
  std::uint64_t seed = 1;
  RateType rate_type = RateType::Imu;
  std::string rate_topic = "/imu/data_raw";
  std::string rate_frame = "";  ///< frame_id of the rate messages
  TruthType truth = TruthType::Pose;
  std::string truth_topic = "/truth";
  double truth_hz = 200.0;
  double truth_offset = 0.0;  ///< s: the truth of instant t is stamped t + truth_offset
  /// rad: each truth sample turned by Exp(n), n with this standard deviation per axis
  double truth_noise = 0.0;
  double gap_from = -1.0, gap_to = -1.0;  ///< s: no truth sample stamped in between
  Eigen::Quaterniond fixed = Eigen::Quaterniond::Identity();  ///< A = q_VW
  Eigen::Quaterniond mount = Eigen::Quaterniond::Identity();  ///< q_ST
  std::vector<long> non_finite;  ///< indices of rate samples written with a NaN component
  std::vector<long> lost;        ///< indices of rate samples not written (lost)
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();  ///< rad/s, added to every rate sample
  /// When set: the truth's attitude q_WS(t) (a truth with errors of its own, or none at all),
  /// in place of the motion's
  std::function<Eigen::Quaterniond(double)> truth_attitude;
  double truth_norm = 1.0;  ///< the truth quaternions' coefficients multiplied by it
  /// TruthType::Imu: orientation_covariance[0] (REP-145: -1 says "no orientation")
  double truth_orientation_covariance = 0.0;
  Compression compression = Compression::None;  ///< of the bag's chunks
};

struct Written {
  std::vector<Stamp> rate_stamps;   ///< as written
  std::vector<double> rate_times;   ///< physical instants of those samples, s
  std::vector<Stamp> truth_stamps;  ///< as written
};

/// The DC group delay, in samples, of the 2nd-order Butterworth low-pass at fc = fraction * fs
/// by the bilinear transform with the cut-off prewarped: sqrt2 / (2 tan(pi fraction)).
double butterworthDelay(double fraction);

/// Writes the scene's bag; q_VT(t) = A q_WS(t) q_ST is the truth of instant t.
Written writeSceneBag(const std::string& path, const SceneBag& scene);

/// A bag with only a torque topic (geometry_msgs/WrenchStamped in frame `frame`, a constant
/// torque from t = 0 at `hz`), and a /clock topic at `clock_hz` when positive.
void writeTorqueBag(const std::string& path, const Eigen::Vector3d& torque, double hz,
                    double duration, double clock_hz, const std::string& frame);

/// Where each chunk's data (compressed or not) lies in a bag file, found by walking its
/// records (independently of the tools' own check).
struct ChunkData {
  std::uint64_t position;
  std::uint64_t size;
};
std::vector<ChunkData> chunkData(const std::string& path);

/// A command's exit status and its output (stdout and stderr together). A command killed by a
/// signal has status -1.
struct RunResult {
  int status = -1;
  std::string output;
};
RunResult run(const std::string& command);

/// Quoting for a shell command line.
std::string quote(const std::string& text);
/// `--set name=[x, y, z, w]` for a tool's command line, every digit of q kept.
std::string setQuaternion(const char* name, const Eigen::Quaterniond& q);
/// A message's quaternion, read here rather than through the message layer the tools use.
Eigen::Quaterniond toEigen(const geometry_msgs::Quaternion& q);

/// A fresh directory under /tmp, removed with everything in it by the destructor (kept when
/// BAG_TESTS_KEEP is set, to look at a test's files).
class TempDir {
 public:
  TempDir();
  ~TempDir();
  std::string file(const std::string& name) const { return path_ + "/" + name; }
  std::vector<std::string> list() const;  ///< names of the files in it

 private:
  std::string path_;
};

/// The programs under test, as built (their paths come from CMake), unless the environment
/// names others: the mutation check (scripts/mutants.sh) runs this suite on tools rebuilt with
/// a mutant, one pair per parallel worker.
inline std::string programPath(const char* variable, const char* built) {
  const char* given = std::getenv(variable);
  return given && *given ? given : built;
}
inline const std::string kPropagate = programPath("AP_PROPAGATE_BAG", PROPAGATE_BAG);
inline const std::string kEvaluateCore = programPath("AP_EVALUATE_BAG_CORE", EVALUATE_BAG_CORE);
inline const std::string kEvaluate = EVALUATE_BAG;

/// Every message of a bag: topic, record time and serialised bytes, in rosbag's time order.
struct Recorded {
  std::string topic;
  ros::Time time;
  std::vector<std::uint8_t> bytes;
  bool operator==(const Recorded& o) const {
    return topic == o.topic && time == o.time && bytes == o.bytes;
  }
};
std::vector<Recorded> readRecorded(const std::string& path);

/// What propagate_bag wrote, decoded: the states, the IMU messages, every transform on /tf in
/// order (one per state unless publish_tf is off) and the messages per topic.
struct OutputBag {
  std::vector<attitude_propagator::AttitudeState> states;
  std::vector<sensor_msgs::Imu> imu;
  std::vector<geometry_msgs::TransformStamped> tf;
  std::map<std::string, std::size_t> count;
};
OutputBag readOutputBag(const std::string& path);

/// No temporary output (".partial") left in the directory.
bool noPartialFiles(const TempDir& dir);

std::string fileText(const std::string& path);
void writeText(const std::string& path, const std::string& text);

/// Rows of a CSV file with a header, as maps from column to text.
std::vector<std::vector<std::pair<std::string, std::string>>> readCsv(const std::string& path);
std::string field(const std::vector<std::pair<std::string, std::string>>& row,
                  const std::string& column);

}  // namespace bagtest
