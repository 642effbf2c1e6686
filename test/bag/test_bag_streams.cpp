// Several input bags read as one stream, and the output options: the parts of a split
// recording must give what the recording gives, every input bag is checked, the output topics
// follow the options, the mounts used reach the output's /tf_static, and the summary accounts
// for every input message.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include <unistd.h>

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

void toMsg(const Eigen::Vector3d& v, geometry_msgs::Vector3& m) {
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
}

void toMsg(const Eigen::Quaterniond& q, geometry_msgs::Quaternion& m) {
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  m.w = q.w();
}

/// A static transform parent -> child, rotation q_PC, as a latched /tf_static records it.
geometry_msgs::TransformStamped edge(const std::string& parent, const std::string& child,
                                     const Eigen::Quaterniond& q_PC, const Eigen::Vector3d& p) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = rosTime(stampAt(0.0));
  t.header.frame_id = parent;
  t.child_frame_id = child;
  toMsg(q_PC, t.transform.rotation);
  toMsg(p, t.transform.translation);
  return t;
}

void writeStatic(rosbag::Bag& bag, const std::vector<geometry_msgs::TransformStamped>& edges) {
  tf2_msgs::TFMessage m;
  m.transforms = edges;
  // A publisher's connection header as `rosbag record` stores it.
  auto header = boost::make_shared<ros::M_string>();
  (*header)["topic"] = "/tf_static";
  (*header)["type"] = ros::message_traits::datatype<tf2_msgs::TFMessage>();
  (*header)["md5sum"] = ros::message_traits::md5sum<tf2_msgs::TFMessage>();
  (*header)["message_definition"] = ros::message_traits::definition<tf2_msgs::TFMessage>();
  (*header)["callerid"] = "/static_transform_publisher";
  (*header)["latching"] = "1";
  bag.write("/tf_static", rosTime(stampAt(0.0)), m, header);
}

// A mount: the IMU frame imu_link under base_link through a plate, q_B,plate and q_plate,I.
const Eigen::Quaterniond kPlate =
    Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
const Eigen::Quaterniond kImuOnPlate =
    Eigen::Quaterniond(Eigen::AngleAxisd(-1.1, Eigen::Vector3d(0, 1, 1).normalized()));

/// 200 Hz IMU messages of the coning body, measured in imu_link (w_I = q_BI^-1 w_B), with the
/// mount in /tf_static as a chain base_link -> plate -> imu_link.
void writeMountedImuBag(const std::string& path, double duration) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  writeStatic(bag, {edge("base_link", "plate", kPlate, Eigen::Vector3d(0.1, 0, 0)),
                    edge("plate", "imu_link", kImuOnPlate, Eigen::Vector3d(0, 0.02, 0))});
  const Motion body = coning();
  const Eigen::Quaterniond q_BI = kPlate * kImuOnPlate;
  for (long k = 0; k <= std::lround(duration * 200); ++k) {
    const double t = k / 200.0;
    sensor_msgs::Imu m;
    m.header.stamp = rosTime(stampAt(t));
    m.header.frame_id = "imu_link";
    toMsg(q_BI.conjugate() * body.rate(t), m.angular_velocity);
    bag.write("/imu/data_raw", m.header.stamp, m);
  }
  bag.close();
}

/// Copies the messages of `in` into parts cut at the given record times (a message at a cut
/// time goes to the later part), with their connection headers (a latched /tf_static stays
/// latched), as `rosbag record --split` cuts a recording.
std::vector<std::string> split(const std::string& in, const std::vector<double>& cuts,
                               const TempDir& dir) {
  std::vector<std::string> paths;
  std::vector<std::unique_ptr<rosbag::Bag>> parts;
  for (std::size_t i = 0; i <= cuts.size(); ++i) {
    paths.push_back(dir.file("part_" + std::to_string(i) + ".bag"));
    parts.push_back(std::make_unique<rosbag::Bag>(paths.back(), rosbag::bagmode::Write));
  }
  rosbag::Bag bag(in, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    std::size_t part = 0;
    while (part < cuts.size() && m.getTime() >= rosTime(stampAt(cuts[part]))) ++part;
    parts[part]->write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
  }
  for (auto& p : parts) p->close();
  return paths;
}

std::map<std::string, std::size_t> topicCounts(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<std::string, std::size_t> count;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) ++count[m.getTopic()];
  return count;
}

std::string join(const std::vector<std::string>& paths) {
  std::string text;
  for (const auto& p : paths) text += " " + quote(p);
  return text;
}

int lines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

// ---------------------------------------------------------------------------------------------
// Split recordings
// ---------------------------------------------------------------------------------------------

// The parts of a split recording, given out of order, give the unsplit recording's output
// byte for byte: the same states (the engine does not start again at a part), the same
// republished IMU messages and tf, and the mount read from /tf_static, which only the first
// part holds (as `rosbag record --split` writes a latched topic once).
TEST(SplitBags, KinematicPartsGiveTheWholeRecording) {
  TempDir dir;
  writeMountedImuBag(dir.file("whole.bag"), 6.0);
  const auto parts = split(dir.file("whole.bag"), {2.0, 4.5}, dir);
  const std::string common = " --set integrator=cf4 --no-progress";
  const RunResult whole =
      run(kPropagate + " " + dir.file("whole.bag") + " -o " + dir.file("a.bag") + common);
  ASSERT_EQ(whole.status, 0) << whole.output;
  const RunResult pieces =
      run(kPropagate + join({parts[2], parts[0], parts[1]}) + " -o " + dir.file("b.bag") + common);
  ASSERT_EQ(pieces.status, 0) << pieces.output;
  EXPECT_EQ(pieces.output.find("share"), std::string::npos) << "parts that touch do not overlap";
  const auto a = readRecorded(dir.file("a.bag"));
  ASSERT_EQ(topicCounts(dir.file("a.bag"))["/attitude_state"], 1201u);
  EXPECT_TRUE(a == readRecorded(dir.file("b.bag")));
}

// The dynamic model on a /clock: a body torqued from rest, the bag cut in two parts. The
// state at every grid stamp is the unsplit run's.
TEST(SplitBags, DynamicPartsGiveTheWholeRecording) {
  TempDir dir;
  writeTorqueBag(dir.file("whole.bag"), Eigen::Vector3d(0, 0, 0.3), 50.0, 6.0, 40.0, "base_link");
  const auto parts = split(dir.file("whole.bag"), {3.01}, dir);
  const std::string common =
      " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none"
      " --set integrator=rk4 --set publish_rate=100 --no-progress";
  const RunResult whole =
      run(kPropagate + " " + dir.file("whole.bag") + " -o " + dir.file("a.bag") + common);
  ASSERT_EQ(whole.status, 0) << whole.output;
  const RunResult pieces =
      run(kPropagate + join({parts[1], parts[0]}) + " -o " + dir.file("b.bag") + common);
  ASSERT_EQ(pieces.status, 0) << pieces.output;
  const auto a = readRecorded(dir.file("a.bag"));
  ASSERT_EQ(topicCounts(dir.file("a.bag"))["/attitude_state"], 601u);
  EXPECT_TRUE(a == readRecorded(dir.file("b.bag")));
}

// evaluate_bag_core over the parts finds the same errors as over the whole bag (the costs per
// sample are timings and differ between any two runs).
TEST(SplitBags, EvaluationOfPartsIsTheWholeRecordings) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 12.0;
  writeSceneBag(dir.file("whole.bag"), scene);
  const auto parts = split(dir.file("whole.bag"), {5.0}, dir);
  const std::string common = " --rates /imu/data_raw --truth /truth --calibration 4 --no-progress";
  const RunResult whole =
      run(kEvaluateCore + " " + dir.file("whole.bag") + common + " --csv " + dir.file("a"));
  ASSERT_EQ(whole.status, 0) << whole.output;
  const RunResult pieces =
      run(kEvaluateCore + join({parts[1], parts[0]}) + common + " --csv " + dir.file("b"));
  ASSERT_EQ(pieces.status, 0) << pieces.output;
  const auto a = readCsv(dir.file("a.csv")), b = readCsv(dir.file("b.csv"));
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (const auto& [column, value] : a[i]) {
      if (column.find("ns") != std::string::npos || column.find("cost") != std::string::npos)
        continue;
      EXPECT_EQ(field(b[i], column), value) << column;
    }
  }
  EXPECT_EQ(fileText(dir.file("a_series.csv")), fileText(dir.file("b_series.csv")));
  // The front end passes every input on and names the outputs after the first.
  const RunResult front =
      run("EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " + quote(kEvaluate) +
          join({parts[1], parts[0]}) + common + " --no-plot");
  EXPECT_EQ(front.status, 0) << front.output;
  EXPECT_EQ(readCsv(dir.file("part_1.evaluation.csv")).size(), a.size());
}

// What a user may get wrong with several inputs: each is one clear line, its exit code, and
// nothing written; the inputs untouched.
TEST(SplitBags, BadInputListsAreRefused) {
  TempDir dir;
  writeMountedImuBag(dir.file("whole.bag"), 2.0);
  const auto parts = split(dir.file("whole.bag"), {1.0}, dir);
  const std::string out = dir.file("out.bag");
  auto refused = [&](const std::string& inputs, int status, const std::string& message,
                     const std::string& output) {
    const RunResult r = run(kPropagate + inputs + " -o " + quote(output));
    EXPECT_EQ(r.status, status) << inputs << "\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
    std::ifstream left(out);
    EXPECT_FALSE(left.good()) << "output left behind";
    EXPECT_TRUE(noPartialFiles(dir));
  };
  // A shell pattern that matched nothing arrives as it is.
  refused(join({parts[0], dir.file("rec_*.bag")}), 1, "a pattern that matched no file", out);
  // The same bag twice, under the same name, "./" or a hard link.
  refused(join({parts[0], parts[1], parts[0]}), 2, "given twice", out);
  ASSERT_EQ(::link(parts[1].c_str(), dir.file("link.bag").c_str()), 0);
  refused(join({parts[0], parts[1], dir.file("link.bag")}), 2, "given twice", out);
  refused(join({parts[0], dir.file("./part_0.bag")}), 2, "given twice", out);
  // An output that is one of the inputs.
  const std::string before = fileText(parts[1]);
  refused(join({parts[0], parts[1]}), 2, "is the input " + parts[1], parts[1]);
  EXPECT_EQ(fileText(parts[1]), before);
  // A damaged part: named, before anything is read.
  const std::string good = fileText(parts[1]);
  writeText(dir.file("cut.bag"), good.substr(0, good.size() / 2));
  refused(join({parts[0], dir.file("cut.bag")}), 1, dir.file("cut.bag") + ": ", out);
  // An unwritable output is named as the user gave it.
  const std::string missing = dir.file("missing/out.bag");
  const RunResult r = run(kPropagate + join(parts) + " -o " + missing);
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_EQ(r.output.find("propagate_bag: " + missing + ": "), 0u) << r.output;
  // evaluate_bag_core reads its inputs the same way.
  const RunResult e = run(kEvaluateCore + join({parts[0], parts[0]}) +
                          " --rates /imu/data_raw --truth /truth --csv " + dir.file("e"));
  EXPECT_EQ(e.status, 2) << e.output;
  EXPECT_NE(e.output.find("given twice"), std::string::npos) << e.output;
}

// ---------------------------------------------------------------------------------------------
// Output options
// ---------------------------------------------------------------------------------------------

// --ns puts the relative outputs in a namespace, as ROS resolves a node's relative names;
// /tf and /tf_static stay; per-topic options override. Clashing or invalid names: usage.
TEST(OutputOptions, TopicsFollowTheNamespaceAndOptions) {
  TempDir dir;
  writeMountedImuBag(dir.file("in.bag"), 1.0);
  const std::string in = dir.file("in.bag") + " --no-progress -o " + dir.file("out.bag");
  RunResult r = run(kPropagate + " " + in + " --ns robot1");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::map<std::string, std::size_t> expected{
      {"/robot1/attitude_state", 201}, {"/robot1/imu/data", 201}, {"/tf", 201}, {"/tf_static", 1}};
  EXPECT_EQ(topicCounts(dir.file("out.bag")), expected);
  r = run(kPropagate + " " + in + " --ns /r2 --state-topic /state --imu-topic imu/out" +
          " --tf-topic tf --tf-static-topic /r2/tf_static");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::map<std::string, std::size_t> remapped{
      {"/state", 201}, {"/r2/imu/out", 201}, {"/r2/tf", 201}, {"/r2/tf_static", 1}};
  EXPECT_EQ(topicCounts(dir.file("out.bag")), remapped);
  for (const char* bad : {" --state-topic /tf", " --imu-topic attitude_state", " --ns 'a b'",
                          " --state-topic '~state'", " --tf-topic 9tf"}) {
    r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("x.bag") + bad);
    EXPECT_EQ(r.status, 2) << bad << "\n" << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
  }
}

// The mount used (base_link -> plate -> imu_link, read from the input's /tf_static) is in the
// output's /tf_static, latched and as recorded: its transforms compose to the mount the bag
// was written with. The output then propagates on its own (its imu/data in imu_link) to the
// same states.
TEST(OutputOptions, MountGoesToTfStatic) {
  TempDir dir;
  writeMountedImuBag(dir.file("in.bag"), 2.0);
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set integrator=cf4 --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  rosbag::Bag bag(dir.file("out.bag"), rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery("/tf_static"));
  ASSERT_EQ(view.size(), 1u);
  const rosbag::MessageInstance m = *view.begin();
  ASSERT_TRUE(m.getConnectionHeader());
  EXPECT_EQ(m.getConnectionHeader()->at("latching"), "1");
  const auto tf = m.instantiate<tf2_msgs::TFMessage>();
  ASSERT_TRUE(tf);
  std::map<std::string, geometry_msgs::TransformStamped> by_child;
  for (const auto& t : tf->transforms) by_child[t.child_frame_id] = t;
  ASSERT_EQ(by_child.size(), 2u);
  EXPECT_EQ(by_child["plate"].header.frame_id, "base_link");
  EXPECT_EQ(by_child["imu_link"].header.frame_id, "plate");
  const Eigen::Quaterniond q_BI = toEigen(by_child["plate"].transform.rotation) *
                                  toEigen(by_child["imu_link"].transform.rotation);
  EXPECT_LT(ap::rotationAngle(q_BI, kPlate * kImuOnPlate), 1e-15);
  EXPECT_EQ(by_child["plate"].transform.translation.x, 0.1);

  const RunResult again = run(kPropagate + " " + dir.file("out.bag") + " --rates /imu/data -o " +
                              dir.file("again.bag") + " --set integrator=cf4 --no-progress");
  ASSERT_EQ(again.status, 0) << again.output;
  EXPECT_NE(again.output.find("401 accepted, dropped: none"), std::string::npos) << again.output;
  rosbag::Bag first(dir.file("out.bag"), rosbag::bagmode::Read);
  rosbag::Bag second(dir.file("again.bag"), rosbag::bagmode::Read);
  std::vector<Eigen::Quaterniond> a, b;
  for (const auto& s : rosbag::View(first, rosbag::TopicQuery("/attitude_state")))
    a.push_back(toEigen(s.instantiate<ap::AttitudeState>()->orientation));
  for (const auto& s : rosbag::View(second, rosbag::TopicQuery("/attitude_state")))
    b.push_back(toEigen(s.instantiate<ap::AttitudeState>()->orientation));
  ASSERT_EQ(a.size(), b.size());
  // The rates went through q_BI and back: round-off only.
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_LT(ap::rotationAngle(a[k], b[k]), 1e-12);
}

/// 200 Hz IMU messages in imu_link, its mount base_link -> imu_link published on /tf at 10 Hz
/// (a driver's broadcaster, not /tf_static), the first one recorded before the first IMU message;
/// and a gyro bias of zero in `bias_frame`.
void writeTfMountedImuBag(const std::string& path, double duration, const std::string& bias_frame) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const Motion body = coning();
  const Eigen::Quaterniond q_BI = kPlate * kImuOnPlate;
  geometry_msgs::Vector3Stamped bias;
  bias.header.stamp = rosTime(stampAt(0.0));
  bias.header.frame_id = bias_frame;
  bag.write("/gyro_bias", bias.header.stamp, bias);
  for (long k = 0; k <= std::lround(duration * 200); ++k) {
    const double t = k / 200.0;
    if (k % 20 == 0) {
      tf2_msgs::TFMessage tf;
      tf.transforms.push_back(edge("base_link", "imu_link", q_BI, Eigen::Vector3d(0.1, 0, 0)));
      // Recorded 1 ms before the IMU message of its instant (a tie in record time has no order).
      tf.transforms.back().header.stamp = rosTime(stampAt(t - 0.001));
      bag.write("/tf", rosTime(stampAt(t - 0.001)), tf);
    }
    sensor_msgs::Imu m;
    m.header.stamp = rosTime(stampAt(t));
    m.header.frame_id = "imu_link";
    toMsg(q_BI.conjugate() * body.rate(t), m.angular_velocity);
    bag.write("/imu/data_raw", m.header.stamp, m);
  }
  bag.close();
}

std::vector<Eigen::Quaterniond> states(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<Eigen::Quaterniond> q;
  for (const auto& s : rosbag::View(bag, rosbag::TopicQuery("/attitude_state")))
    q.push_back(toEigen(s.instantiate<ap::AttitudeState>()->orientation));
  return q;
}

// A mount on /tf is heard as the node's listener hears it: every message is propagated, to the
// states the same mount on /tf_static gives; /tf is no input (not in the summary's count).
TEST(Frames, MountOnTfAsTheNodeHearsIt) {
  TempDir dir;
  writeTfMountedImuBag(dir.file("tf.bag"), 2.0, "base_link");
  writeMountedImuBag(dir.file("static.bag"), 2.0);
  const std::string options = " --set integrator=cf4 --no-progress";
  const RunResult r =
      run(kPropagate + " " + dir.file("tf.bag") + " -o " + dir.file("tf_out.bag") + options);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("402 messages (/gyro_bias 1, /imu/data_raw 401), 401 accepted, "
                          "dropped: none"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("gyro bias: bias_applied 1, rejected_bias 0"), std::string::npos)
      << r.output;
  const RunResult s = run(kPropagate + " " + dir.file("static.bag") + " -o " +
                          dir.file("static_out.bag") + options);
  ASSERT_EQ(s.status, 0) << s.output;
  const std::vector<Eigen::Quaterniond> a = states(dir.file("tf_out.bag"));
  const std::vector<Eigen::Quaterniond> b = states(dir.file("static_out.bag"));
  ASSERT_EQ(a.size(), 401u);
  ASSERT_EQ(a.size(), b.size());
  // One mount composed by tf2 from one edge or from two: round-off only.
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_LT(ap::rotationAngle(a[k], b[k]), 1e-12);
}

// A gyro bias in a frame that is neither the body nor the rates' mount is refused, as the node
// refuses it, and counted once: as a refused bias, not as a dropped input.
TEST(Frames, BiasInAnotherFrameRefusedOnce) {
  TempDir dir;
  writeTfMountedImuBag(dir.file("in.bag"), 1.0, "elsewhere");
  const RunResult r =
      run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("201 accepted, dropped: none"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gyro bias: bias_applied 0, rejected_bias 1"), std::string::npos)
      << r.output;
}

// 65 bias samples stamped an hour ahead of the rates: none takes effect before its stamp (the
// 65th finds the queue of 64 full and is dropped, counted), so the body stays at rest and the
// summary counts no bias as used.
TEST(Frames, BiasAheadOfTheRatesNeverTakesEffectEarly) {
  TempDir dir;
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    geometry_msgs::Vector3Stamped bias;
    bias.header.stamp = rosTime(stampAt(3600.0));
    bias.header.frame_id = "base_link";
    bias.vector.z = 1.0;
    for (int k = 0; k < 65; ++k) bag.write("/gyro_bias", rosTime(stampAt(0.0)), bias);
    for (int k = 0; k <= 100; ++k) {
      sensor_msgs::Imu m;  // at rest
      m.header.stamp = rosTime(stampAt(0.01 * k));
      m.header.frame_id = "base_link";
      bag.write("/imu/data_raw", m.header.stamp, m);
    }
  }
  const RunResult r =
      run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("gyro bias: bias_applied 0, rejected_bias 0"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("bias_queue_full 1"), std::string::npos) << r.output;
  const std::vector<Eigen::Quaterniond> q = states(dir.file("out.bag"));
  ASSERT_FALSE(q.empty());
  EXPECT_LT(ap::rotationAngle(q.back(), Eigen::Quaterniond::Identity()), 1e-12);
}

/// The numbers of the summary's "inputs: N = A accepted + D dropped + P pending" line, and
/// the named drops of its first line.
struct Account {
  long inputs = -1, accepted = -1, dropped = -1, pending = -1;
  std::map<std::string, long> drops;
  bool unaccounted = false;
};

Account account(const std::string& output) {
  Account a;
  std::smatch m;
  if (std::regex_search(
          output, m, std::regex(R"(inputs: (\d+) = (\d+) accepted \+ (\d+) dropped \+ (\d+))"))) {
    a.inputs = std::stol(m[1]);
    a.accepted = std::stol(m[2]);
    a.dropped = std::stol(m[3]);
    a.pending = std::stol(m[4]);
  }
  if (std::regex_search(output, m, std::regex(R"(dropped: ([^;]*);)"))) {
    const std::string list = m[1];
    const std::regex item(R"(([a-z_]+) (\d+))");
    for (auto it = std::sregex_iterator(list.begin(), list.end(), item);
         it != std::sregex_iterator(); ++it) {
      a.drops[(*it)[1]] = std::stol((*it)[2]);
    }
  }
  a.unaccounted = output.find("not accounted for") != std::string::npos;
  return a;
}

// Kinematic: 1001 IMU messages of which 7 stragglers (stamped before the message before), 5
// in a frame with no transform, 3 with a NaN rate and 2 marking their rate unavailable
// (REP-145). Each is counted under its reason, and the counts add up to the messages read.
TEST(Summary, KinematicCountsAddUpToTheMessagesRead) {
  TempDir dir;
  rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
  const Motion body = coning();
  long written = 0;
  for (long k = 0; k <= 1000; ++k) {
    const double t = k / 200.0;
    sensor_msgs::Imu m;
    m.header.stamp = rosTime(stampAt(t));
    m.header.frame_id = "base_link";
    toMsg(body.rate(t), m.angular_velocity);
    if (k % 100 == 50 && k < 750) m.header.stamp = rosTime(stampAt(t - 0.0125));  // 7 dropped_stale
    if (k % 100 == 60 && k < 560) m.header.frame_id = "nowhere";                  // 5 dropped_no_tf
    if (k % 100 == 70 && k < 370) m.angular_velocity.y = std::nan("");            // 3
    if (k % 100 == 80 && k < 280) m.angular_velocity_covariance[0] = -1;          // 2
    bag.write("/imu/data_raw", rosTime(stampAt(t)), m);
    ++written;
  }
  bag.close();
  const RunResult r =
      run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const Account a = account(r.output);
  EXPECT_EQ(a.inputs, written) << r.output;
  EXPECT_EQ(a.accepted + a.dropped + a.pending, written) << r.output;
  EXPECT_FALSE(a.unaccounted) << r.output;
  EXPECT_EQ(a.pending, 0);
  EXPECT_EQ(a.accepted, written - 17);
  const std::map<std::string, long> drops{{"dropped_stale", 7},
                                          {"dropped_no_tf", 5},
                                          {"rejected_non_finite", 3},
                                          {"rejected_no_rate", 2}};
  EXPECT_EQ(a.drops, drops) << r.output;
}

/// A publisher's connection header for a message of type M on `topic`, as `rosbag record`
/// stores it: two publishers of two types on one topic are two connections of the bag.
template <class M>
boost::shared_ptr<ros::M_string> publisherHeader(const std::string& topic,
                                                 const std::string& caller) {
  auto header = boost::make_shared<ros::M_string>();
  (*header)["topic"] = topic;
  (*header)["type"] = ros::message_traits::datatype<M>();
  (*header)["md5sum"] = ros::message_traits::md5sum<M>();
  (*header)["message_definition"] = ros::message_traits::definition<M>();
  (*header)["callerid"] = caller;
  return header;
}

// rate_input twist: a topic keeps the type of its first message (docs/node.md), so 10
// geometry_msgs/Twist from a second publisher among 201 TwistStamped are refused, counted as
// "type" and in the account.
TEST(Summary, WrongTypeCountedInTheAccount) {
  TempDir dir;
  rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
  const auto stamped = publisherHeader<geometry_msgs::TwistStamped>("/body_twist", "/driver");
  const auto plain = publisherHeader<geometry_msgs::Twist>("/body_twist", "/teleop");
  const Motion body = coning();
  for (long k = 0; k <= 200; ++k) {
    const double t = k / 200.0;
    geometry_msgs::TwistStamped m;
    m.header.stamp = rosTime(stampAt(t));
    toMsg(body.rate(t), m.twist.angular);
    bag.write("/body_twist", m.header.stamp, m, stamped);
    if (k % 20 != 10) continue;
    geometry_msgs::Twist other;  // recorded just after, on the same topic
    toMsg(body.rate(t), other.angular);
    bag.write("/body_twist", rosTime(stampAt(t + 0.001)), other, plain);
  }
  bag.close();
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set rate_input=twist --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const Account a = account(r.output);
  EXPECT_EQ(a.inputs, 211) << r.output;
  EXPECT_EQ(a.accepted, 201) << r.output;
  EXPECT_EQ(a.accepted + a.dropped + a.pending, a.inputs) << r.output;
  EXPECT_FALSE(a.unaccounted) << r.output;
  const std::map<std::string, long> drops{{"rejected_type", 10}};
  EXPECT_EQ(a.drops, drops) << r.output;
}

// Dynamic, on a 100 Hz /clock over 4 s: 201 torques at 50 Hz; 4 stragglers, 3 stamped 5 s
// ahead of the clock (refused: max_future 1 s), and 6 recorded after the last clock tick and
// stamped after it (pending at the end). Every torque is accounted for.
TEST(Summary, DynamicCountsAddUpToTheMessagesRead) {
  TempDir dir;
  rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
  long written = 0;
  auto torque = [&](double record, double stamp) {
    geometry_msgs::WrenchStamped m;
    m.header.stamp = rosTime(stampAt(stamp));
    m.header.frame_id = "base_link";
    m.wrench.torque.z = 0.3;
    bag.write("/torque", rosTime(stampAt(record)), m);
    ++written;
  };
  for (long k = 0; k <= 400; ++k) {
    rosgraph_msgs::Clock c;
    c.clock = rosTime(stampAt(k / 100.0));
    bag.write("/clock", c.clock, c);
    if (k % 2 != 0) continue;
    const double t = k / 100.0;
    const bool straggler = k % 100 == 50;          // 4: stamped before the torque before it
    const bool future = k % 100 == 24 && k < 300;  // 3
    torque(t + 0.005, straggler ? t - 0.03 : future ? t + 5.0 : t);
  }
  for (int i = 1; i <= 6; ++i) torque(4.0 + 0.01 * i, 4.0 + 0.02 * i);
  bag.close();
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none"
                          " --set integrator=rk4 --set publish_rate=100 --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const Account a = account(r.output);
  EXPECT_EQ(a.inputs, written) << r.output;
  EXPECT_EQ(a.accepted + a.dropped + a.pending, written) << r.output;
  EXPECT_FALSE(a.unaccounted) << r.output;
  EXPECT_EQ(a.pending, 6) << r.output;
  const std::map<std::string, long> drops{{"dropped_stale", 4}, {"rejected_future", 3}};
  EXPECT_EQ(a.drops, drops) << r.output;
  EXPECT_NE(r.output.find("dynamic: failed_steps 0, pending 6"), std::string::npos) << r.output;
}

// A /clock that jumps back 2 s (a looped recording) resets the engine, and the torques that
// were waiting for the clock go with the reset: counted as "reset", so the account still
// adds up. Torques are stamped 0.5 s ahead of the clock at 50 Hz: 25 wait at the jump, and 25
// at the end.
TEST(Summary, ClockJumpBackLosesNoInputUncounted) {
  TempDir dir;
  rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
  long written = 0;
  for (long k = 0; k <= 300; ++k) {
    const ros::Time record = rosTime(stampAt(k / 100.0));
    const double clock = k <= 200 ? k / 100.0 : (k - 201) / 100.0;
    rosgraph_msgs::Clock c;
    c.clock = rosTime(stampAt(clock));
    bag.write("/clock", record, c);
    if (k % 2 != 0) continue;
    geometry_msgs::WrenchStamped m;
    m.header.stamp = rosTime(stampAt(clock + 0.5));
    m.header.frame_id = "base_link";
    m.wrench.torque.z = 0.3;
    bag.write("/torque", record, m);
    ++written;
  }
  bag.close();
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none"
                          " --set integrator=rk4 --set publish_rate=100 --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const Account a = account(r.output);
  EXPECT_EQ(a.inputs, written) << r.output;
  EXPECT_EQ(a.accepted + a.dropped + a.pending, written) << r.output;
  EXPECT_FALSE(a.unaccounted) << r.output;
  const std::map<std::string, long> drops{{"dropped_on_reset", 25}};
  EXPECT_EQ(a.drops, drops) << r.output;
  EXPECT_EQ(a.pending, 25) << r.output;
}

// Two /clock publishers recorded together (a stale simulator 5 s behind the bag being played),
// ticks interleaved at 100 Hz each over 10 s: ROS time's rule (docs/node.md) costs one reset at
// most, the later timeline is followed, and the summary names both publishers. A sphere turning
// at 0.5 rad/s about z from the last anchor: states are published on the later timeline.
TEST(Summary, TwoClockPublishersCostOneResetAndAreNamed) {
  TempDir dir;
  rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
  auto header = [](const char* callerid) {
    auto h = boost::make_shared<ros::M_string>();
    (*h)["callerid"] = callerid;
    (*h)["type"] = ros::message_traits::datatype<rosgraph_msgs::Clock>();
    (*h)["md5sum"] = ros::message_traits::md5sum<rosgraph_msgs::Clock>();
    (*h)["message_definition"] = ros::message_traits::definition<rosgraph_msgs::Clock>();
    return h;
  };
  const auto play = header("/play"), sim = header("/stale_sim");
  for (long k = 0; k < 1000; ++k) {
    rosgraph_msgs::Clock c;
    c.clock = rosTime(stampAt(5.0 + k / 100.0));
    bag.write("/clock", c.clock, c, play);
    c.clock = rosTime(stampAt(k / 100.0));
    bag.write("/clock", rosTime(stampAt(5.0 + k / 100.0)), c, sim);
    if (k % 10 != 0) continue;
    geometry_msgs::WrenchStamped m;  // no torque, stamped on the later timeline
    m.header.stamp = rosTime(stampAt(5.0 + k / 100.0));
    m.header.frame_id = "base_link";
    bag.write("/torque", m.header.stamp, m);
  }
  bag.close();
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[1,1,1] --set rate_input=none --set torque_input=true"
                          " --set initial_angular_velocity=[0,0,0.5] --set publish_rate=100"
                          " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("; resets (\\d+),"))) << r.output;
  EXPECT_LE(std::stol(m[1]), 1) << r.output;
  EXPECT_NE(r.output.find("clock: two timelines took turns on /clock, 5.000 s apart (followed: "
                          "/play, other: /stale_sim): 1 times recognised"),
            std::string::npos)
      << r.output;
  // The states: the later timeline's grid, each stamp once and increasing after the one reset.
  std::vector<Stamp> stamps;
  for (const auto& state : readOutputBag(dir.file("out.bag")).states)
    stamps.push_back(static_cast<Stamp>(state.header.stamp.toNSec()));
  ASSERT_GT(stamps.size(), 900u) << r.output;
  int back = 0;
  for (std::size_t i = 1; i < stamps.size(); ++i) back += stamps[i] <= stamps[i - 1];
  EXPECT_LE(back, 1) << r.output;
  EXPECT_EQ(stamps.back(), stampAt(5.0 + 9.99)) << r.output;
}

// imu/data with stamp_filter sensor_clock through rate changes (100 Hz, 5 kHz, 100 Hz), the
// receipt stamps up to several 5 kHz periods late: no stamp is published twice (docs/node.md),
// every republished IMU message later than the one before.
TEST(Summary, RateChangesRepeatNoImuStampWithTheStampFilter) {
  TempDir dir;
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    std::mt19937 random(3);
    std::normal_distribution<double> normal;
    Stamp receipt = 0;
    double t = 0.0;
    auto run = [&](double period, double seconds) {
      const long n = std::lround(seconds / period);
      for (long k = 0; k < n; ++k, t += period) {
        receipt = std::max(receipt + 1, stampAt(t + 5e-4 + 3e-3 * std::abs(normal(random))));
        sensor_msgs::Imu m;
        m.header.stamp = rosTime(receipt);
        m.header.frame_id = "base_link";
        m.angular_velocity.z = 0.3;
        bag.write("/imu/data_raw", m.header.stamp, m);
      }
    };
    run(0.01, 5.0);
    run(0.0002, 2.0);
    run(0.01, 5.0);
  }
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set stamp_filter=sensor_clock --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(dir.file("out.bag"));
  ASSERT_GT(out.imu.size(), 10000u) << r.output;
  std::size_t repeated = 0;
  for (std::size_t i = 1; i < out.imu.size(); ++i)
    repeated += out.imu[i].header.stamp <= out.imu[i - 1].header.stamp;
  EXPECT_EQ(repeated, 0u) << r.output;
}

// The quadrotor's stream: 50 Hz received with a latency spread of 0.6 periods (bursts and
// pauses), and a dropout of 0.999 s, under max_dt. With the stamp filter on, the summary says it
// fell back to the receipt stamps once and counts the dropout as a gap (held, not integrated
// across: kGapPeriods); the attitude keeps no rotation from across it (the rate is 0.3 rad/s
// before and 3 rad/s after, so integrating across would add 3 rad).
TEST(Summary, StampFilterFallbackAndDropoutAreReported) {
  TempDir dir;
  const double period = 0.02;
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    std::mt19937 random(5);
    std::normal_distribution<double> normal;
    Stamp receipt = 0;
    for (long k = 0; k < 1500; ++k) {
      const double t = period * k + (k >= 750 ? 0.999 - period : 0.0);
      receipt = std::max(receipt + 1000, stampAt(t + 0.6 * period * std::abs(normal(random))));
      sensor_msgs::Imu m;
      m.header.stamp = rosTime(receipt);
      m.header.frame_id = "base_link";
      m.angular_velocity.z = k < 750 ? 0.3 : 3.0;
      bag.write("/imu/data_raw", m.header.stamp, m);
    }
  }
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " --csv " + dir.file("out.csv") +
                          " --set stamp_filter=sensor_clock --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(" gaps 1,"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 fallbacks to the receipt stamps (in one at the end"),
            std::string::npos)
      << r.output;
  // Yaw at the first state after the dropout: what the rates before it turned, nothing more.
  const auto rows = readCsv(dir.file("out.csv"));
  ASSERT_EQ(rows.size(), 1500u) << r.output;
  auto q = [&rows](std::size_t k) {
    return Eigen::Quaterniond(std::stod(field(rows[k], "qw")), std::stod(field(rows[k], "qx")),
                              std::stod(field(rows[k], "qy")), std::stod(field(rows[k], "qz")));
  };
  EXPECT_GT(std::stod(field(rows[750], "stamp")) - std::stod(field(rows[749], "stamp")), 0.9);
  EXPECT_LT(ap::rotationAngle(q(749), q(750)), 1e-12) << r.output;
}

// ---------------------------------------------------------------------------------------------
// --version, --dry-run, --help
// ---------------------------------------------------------------------------------------------

TEST(ToolOptions, VersionIsThePackageVersion) {
  std::smatch m;
  const std::string xml = fileText(PACKAGE_XML);
  ASSERT_TRUE(std::regex_search(xml, m, std::regex("<version>([^<]+)</version>")));
  const std::string version = m[1];
  const std::string front =
      "EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " + quote(kEvaluate);
  for (const std::string& tool : {kPropagate, kEvaluateCore, front}) {
    const RunResult r = run(tool + " --version");
    EXPECT_EQ(r.status, 0) << tool << "\n" << r.output;
    EXPECT_NE(r.output.find(" " + version + "\n"), std::string::npos) << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
  }
}

// --dry-run checks the bags and prints what would run; it writes nothing, and refuses what
// the run would refuse.
TEST(ToolOptions, DryRunWritesNothing) {
  TempDir dir;
  writeMountedImuBag(dir.file("in.bag"), 2.0);
  const auto parts = split(dir.file("in.bag"), {1.0}, dir);
  const auto before = dir.list();
  const RunResult r = run(kPropagate + join(parts) + " --dry-run --set integrator=exp2");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(dir.list(), before);
  for (const std::string& text :
       {std::string("dry run, nothing written"), parts[0] + ": 201 messages",
        parts[1] + ": 201 messages", std::string("/imu/data_raw"), std::string("sensor_msgs/Imu"),
        std::string("200  rates"), std::string("/tf_static"), std::string("model kinematic"),
        std::string("integrator exp2"), std::string("body_frame base_link"), std::string("max_dt"),
        std::string("part_0.propagated.bag"), std::string("/attitude_state")}) {
    EXPECT_NE(r.output.find(text), std::string::npos) << text << "\n" << r.output;
  }
  const RunResult missing = run(kPropagate + join(parts) + " --dry-run --rates /nothing");
  EXPECT_EQ(missing.status, 1) << missing.output;
  EXPECT_EQ(dir.list(), before);
}

// rosbag's habits: `--key=value` is `--key value` in both programs; evaluate_bag with no
// argument is a usage error (exit 2) with its usage, not a success.
TEST(ToolOptions, KeyEqualsValueIsTheOptionAndItsValue) {
  TempDir dir;
  writeMountedImuBag(dir.file("in.bag"), 1.0);
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " --output=" + dir.file("y.bag") +
                          " --set=integrator=exp2 --dry-run");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find(dir.file("y.bag")), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("integrator exp2"), std::string::npos) << r.output;
  const RunResult wrong = run(kPropagate + " " + dir.file("in.bag") + " --set=integrator=bogus");
  EXPECT_EQ(wrong.status, 2) << wrong.output;
  const RunResult core = run(kEvaluateCore + " " + dir.file("in.bag") + " --max-offset=bogus");
  EXPECT_EQ(core.status, 2) << core.output;
  EXPECT_NE(core.output.find("--max-offset: 'bogus' is not a finite number"), std::string::npos)
      << core.output;
}

TEST(ToolOptions, EvaluateBagWithNoArgumentIsAUsageError) {
  const std::string front =
      "EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " + quote(kEvaluate);
  const RunResult r = run(front);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("no input bag"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--truth"), std::string::npos) << r.output;  // the usage
}

// scene_publisher --help prints its help and exits, with no master (before: it waited for one
// and then published).
TEST(ToolOptions, ScenePublisherHelpPrintsAndExits) {
  const std::string scene_publisher =
      kEvaluate.substr(0, kEvaluate.rfind('/') + 1) + "scene_publisher";
  const RunResult r = run("ROS_MASTER_URI=http://127.0.0.1:1 timeout 20 /usr/bin/python3 " +
                          quote(scene_publisher) + " --help");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("~scene:"), std::string::npos) << r.output;
}

TEST(ToolOptions, HelpNamesTheNewOptions) {
  const RunResult r = run(kPropagate + " --help");
  ASSERT_EQ(r.status, 0);
  for (const char* text :
       {"IN2.bag", "--ns NS", "--state-topic", "--imu-topic", "--tf-topic", "--tf-static-topic",
        "--dry-run", "--version", "lz4", "faster in wall time only"}) {
    EXPECT_NE(r.output.find(text), std::string::npos) << text;
  }
}

}  // namespace

// The dynamic model on a /clock, a body spinning at 1 rad/s about z from its first rate: a rate
// recorded after the grid reached 0.1 s but stamped 0.05 s is late; it acts from the grid point,
// and its message goes out on imu/data with the orientation at its own stamp, 0.05 rad (the
// closed form), not the 0.1 rad of the model's time.
TEST(DynamicLateInput, ItsImuMessageCarriesTheOrientationAtItsOwnStamp) {
  TempDir dir;
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    auto rate = [&bag](double stamp, double recorded) {
      sensor_msgs::Imu m;
      m.header.stamp = rosTime(stampAt(stamp));
      m.header.frame_id = "base_link";
      m.orientation_covariance[0] = -1.0;
      m.angular_velocity.z = 1.0;
      bag.write("/imu/data_raw", rosTime(stampAt(recorded)), m);
    };
    for (int k = 0; k <= 20; ++k) {
      rosgraph_msgs::Clock c;
      c.clock = rosTime(stampAt(0.01 * k));
      bag.write("/clock", c.clock, c);
      if (k == 0) rate(0.0, 0.0);
      if (k == 10) rate(0.05, 0.1005);  // after the tick at 0.1 s, stamped half-way back
    }
    bag.close();
  }
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[1,1,1] --set rate_input=imu --set integrator=rk4"
                          " --set publish_rate=100 --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(dir.file("out.bag"));
  ASSERT_EQ(out.imu.size(), 2u) << r.output;
  const sensor_msgs::Imu& late = out.imu[1];
  EXPECT_EQ(late.header.stamp, rosTime(stampAt(0.05)));
  const Eigen::Quaterniond q = toEigen(late.orientation);
  const Eigen::Quaterniond truth(Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()));
  EXPECT_LE(q.angularDistance(truth), 1e-9) << q.coeffs().transpose();
}
