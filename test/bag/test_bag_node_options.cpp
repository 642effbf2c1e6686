// The node's output options through propagate_bag: each one gives what docs/node.md says the node
// publishes with it. /tf is fixed_frame -> body_frame, rotation only, and with reverse_tf the
// inverse, from the body (in REP-103's axes whatever world_frame is); publish_tf false writes no
// /tf; the dynamic model publishes at every stamp that is a whole multiple of 1/publish_rate,
// once (design.md §5.3: g_k = round(k 1e9 / publish_rate) ns). The output topics' options are in
// test_bag_streams.cpp (OutputOptions), world_frame's axes in test_bag_tools.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

double secondsAt(const ros::Time& stamp) { return secondsOf(static_cast<Stamp>(stamp.toNSec())); }

/// A coning IMU bag (200 Hz, 3 s) and the command that propagates it from the cone's attitude.
struct ConingRun {
  TempDir dir;
  SceneBag scene;
  Written written;
  std::string command;

  ConingRun() {
    scene.motion = coning();
    scene.duration = 3.0;
    scene.truth = TruthType::None;
    written = writeSceneBag(dir.file("in.bag"), scene);
    command = kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
              " --set integrator=cf4 --no-progress";
  }
};

}  // namespace

// reverse_tf: /tf holds body_frame -> fixed_frame with q_BW = q_WB^-1 (the closed form's
// inverse), one transform per state at its stamp; attitude_state stays q_WB in world -> base_link.
TEST(NodeOptions, ReverseTfWritesTheInverseFromTheBody) {
  ConingRun run_;
  const auto& motion = run_.scene.motion;
  const RunResult r = run(run_.command + " --set reverse_tf=true" +
                          setQuaternion("initial_orientation", motion.attitude(0.0)));
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(run_.dir.file("out.bag"));
  ASSERT_EQ(out.states.size(), run_.written.rate_stamps.size());
  ASSERT_EQ(out.tf.size(), out.states.size());
  double worst_tf = 0.0, worst_state = 0.0;
  for (std::size_t k = 0; k < out.tf.size(); ++k) {
    const auto& t = out.tf[k];
    EXPECT_EQ(t.header.frame_id, "base_link");
    EXPECT_EQ(t.child_frame_id, "world");
    EXPECT_EQ(t.header.stamp, out.states[k].header.stamp);
    const double s = secondsAt(t.header.stamp);
    worst_tf = std::max(
        worst_tf, ap::rotationAngle(toEigen(t.transform.rotation), motion.attitude(s).conjugate()));
    EXPECT_EQ(out.states[k].header.frame_id, "world");
    EXPECT_EQ(out.states[k].child_frame_id, "base_link");
    worst_state = std::max(
        worst_state, ap::rotationAngle(toEigen(out.states[k].orientation), motion.attitude(s)));
  }
  EXPECT_LT(worst_tf, 1e-6);
  EXPECT_LT(worst_state, 1e-6);
}

// reverse_tf with world_frame ned: /tf stays in REP-103's frames (base_link -> world, the ENU
// closed form inverted); only attitude_state and /tf_static name NED/FRD axes.
TEST(NodeOptions, ReverseTfWithNedKeepsTfInRep103Axes) {
  ConingRun run_;
  const auto& motion = run_.scene.motion;
  const Eigen::Quaterniond q_NE(0.0, std::sqrt(0.5), std::sqrt(0.5), 0.0);
  const Eigen::Quaterniond q_FB(0.0, 1.0, 0.0, 0.0);
  const RunResult r = run(run_.command + " --set reverse_tf=true --set world_frame=ned" +
                          setQuaternion("initial_orientation", q_NE * motion.attitude(0.0) * q_FB));
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(run_.dir.file("out.bag"));
  ASSERT_EQ(out.tf.size(), out.states.size());
  double worst = 0.0;
  for (const auto& t : out.tf) {
    EXPECT_EQ(t.header.frame_id, "base_link");
    EXPECT_EQ(t.child_frame_id, "world");
    worst =
        std::max(worst, ap::rotationAngle(toEigen(t.transform.rotation),
                                          motion.attitude(secondsAt(t.header.stamp)).conjugate()));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_EQ(out.states.front().header.frame_id, "world_ned");
  EXPECT_EQ(out.count.at("/tf_static"), 1u);
}

// imu/data is reported in the IMU's frame with the orientation of that frame (docs/node.md):
// an IMU mounted at q_BI (base_link -> imu_link on /tf_static) measuring w_I = q_BI^-1 w_B of
// the cone gives q_WI = q_WB q_BI, the state's orientation times the mount.
TEST(NodeOptions, ImuOutputCarriesTheMountedFramesOrientation) {
  TempDir dir;
  const Motion body = coning();
  const Eigen::Quaterniond q_BI(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    tf2_msgs::TFMessage mount;
    mount.transforms = {mountTransform("base_link", "imu_link", q_BI, stampAt(0.0))};
    bag.write("/tf_static", rosTime(stampAt(0.0)), mount);
    for (long k = 0; k <= 400; ++k) {
      const double time = k / 200.0;
      sensor_msgs::Imu m;
      m.header.stamp = rosTime(stampAt(time));
      m.header.frame_id = "imu_link";
      const Eigen::Vector3d w_I = q_BI.conjugate() * body.rate(time);
      m.angular_velocity.x = w_I.x();
      m.angular_velocity.y = w_I.y();
      m.angular_velocity.z = w_I.z();
      bag.write("/imu/data_raw", m.header.stamp, m);
    }
  }
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set integrator=cf4 --no-progress" +
                          setQuaternion("initial_orientation", body.attitude(0.0)));
  ASSERT_EQ(r.status, 0) << r.output;
  rosbag::Bag out(dir.file("out.bag"), rosbag::bagmode::Read);
  std::vector<sensor_msgs::Imu> imu;
  for (const auto& m : rosbag::View(out, rosbag::TopicQuery("/imu/data"))) {
    imu.push_back(*m.instantiate<sensor_msgs::Imu>());
  }
  ASSERT_EQ(imu.size(), 401u);
  double worst = 0.0;
  for (const auto& m : imu) {
    EXPECT_EQ(m.header.frame_id, "imu_link");
    worst = std::max(worst, ap::rotationAngle(toEigen(m.orientation),
                                              body.attitude(secondsAt(m.header.stamp)) * q_BI));
  }
  EXPECT_LT(worst, 1e-6);
}

// publish_tf false: no /tf at all; the states and the republished IMU messages as before.
TEST(NodeOptions, PublishTfOffWritesNoTf) {
  ConingRun run_;
  const RunResult r = run(run_.command + " --set publish_tf=false");
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(run_.dir.file("out.bag"));
  const std::size_t n = run_.written.rate_stamps.size();
  const std::map<std::string, std::size_t> expected{{"/attitude_state", n}, {"/imu/data", n}};
  EXPECT_EQ(out.count, expected);
}

// The dynamic model's grid: a body from rest under a constant torque T about z (I_z = 4),
// torques every 20 ms (50 Hz) and publish_rate 40 Hz. One state at each multiple of 25 ms from
// the first torque to the last, each once, in order, and q = Exp(T t^2 / (2 I_z) z).
TEST(NodeOptions, DynamicStatesAtEveryMultipleOfThePublishPeriod) {
  TempDir dir;
  const double T = 0.3, I = 4.0, duration = 4.0, rate = 40.0;
  writeTorqueBag(dir.file("in.bag"), Eigen::Vector3d(0, 0, T), 50.0, duration, 0.0, "base_link");
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none"
                          " --set integrator=rk4 --set publish_rate=40 --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(dir.file("out.bag"));
  ASSERT_EQ(out.states.size(), std::size_t(duration * rate) + 1) << r.output;
  const Motion truth = torquedFromRest(Eigen::Vector3d::UnitZ(), T, I);
  double worst = 0.0;
  for (std::size_t k = 0; k < out.states.size(); ++k) {
    // kStart is a whole second: the grid stamp k / 40 s from it is k * 25 ms.
    ASSERT_EQ(static_cast<Stamp>(out.states[k].header.stamp.toNSec()),
              kStart + static_cast<Stamp>(k) * 25000000)
        << k;
    worst = std::max(worst, ap::rotationAngle(toEigen(out.states[k].orientation),
                                              truth.attitude(0.025 * double(k))));
  }
  EXPECT_LT(worst, 1e-9);
}

// Sparse torques (every 2 s, max_dt 5 s) at publish_rate 1000 Hz: 2000 grid stamps between two
// inputs, more than the engine publishes in one call (grid_budget, 1000). The node's clock
// ticks often enough that none is left behind; propagate_bag, driven by the input stamps,
// must tick as often: every millisecond from the first torque to the last has its state.
TEST(NodeOptions, DynamicGridCompleteBetweenSparseInputs) {
  TempDir dir;
  const double T = 0.3, I = 4.0, duration = 6.0;
  writeTorqueBag(dir.file("in.bag"), Eigen::Vector3d(0, 0, T), 0.5, duration, 0.0, "base_link");
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none"
                          " --set integrator=rk4 --set publish_rate=1000 --set max_dt=5"
                          " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const OutputBag out = readOutputBag(dir.file("out.bag"));
  ASSERT_EQ(out.states.size(), std::size_t(duration * 1000) + 1) << r.output;
  for (std::size_t k = 0; k < out.states.size(); ++k) {
    ASSERT_EQ(static_cast<Stamp>(out.states[k].header.stamp.toNSec()),
              kStart + static_cast<Stamp>(k) * 1000000)
        << k;
  }
  const Motion truth = torquedFromRest(Eigen::Vector3d::UnitZ(), T, I);
  EXPECT_LT(ap::rotationAngle(toEigen(out.states.back().orientation), truth.attitude(duration)),
            1e-9);
}
