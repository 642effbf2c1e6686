// logText (src/ros/log_text.cpp): what a message's string becomes in a log line; the lines
// composed for the log: noteText (note_text.cpp), the input lines (input_text.cpp).
#include <iterator>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/ros/input_text.h"
#include "attitude_propagator/ros/log_text.h"
#include "attitude_propagator/ros/note_text.h"

namespace ap = attitude_propagator;

TEST(LogText, ShortTextIsKept) {
  EXPECT_EQ(ap::logText(""), "");
  EXPECT_EQ(ap::logText("base_link"), "base_link");
  const std::string limit(ap::kLogTextBytes, 'a');
  EXPECT_EQ(ap::logText(limit), limit);
}

TEST(LogText, LongTextIsCutWithItsLength) {
  const std::string huge(10 * 1000 * 1000, 'x');
  EXPECT_EQ(ap::logText(huge), std::string(ap::kLogTextBytes, 'x') + "...(10000000 bytes)");
  EXPECT_EQ(ap::logText(std::string(ap::kLogTextBytes + 1, 'y')),
            std::string(ap::kLogTextBytes, 'y') + "...(65 bytes)");
  EXPECT_EQ(ap::logText("abcdef", 3), "abc...(6 bytes)");
}

TEST(LogText, ControlCharactersCannotStartALineOfTheirOwn) {
  EXPECT_EQ(ap::logText("a\nb\r\x1b[31m\x7f\t"), "a?b??[31m??");
  EXPECT_EQ(ap::logText(std::string("nul\0byte", 8)), "nul?byte");
}

TEST(LogText, TheCutEndsOnAWholeUtf8Character) {
  // "é" is two bytes (C3 A9): 63 bytes of 'a' then "é" would be cut inside it at 64.
  const std::string text = std::string(ap::kLogTextBytes - 1, 'a') + "\xC3\xA9" + "tail";
  EXPECT_EQ(ap::logText(text), std::string(ap::kLogTextBytes - 1, 'a') + "...(69 bytes)");
  // "€" is three bytes (E2 82 AC); three of them in 8 bytes: two whole ones.
  EXPECT_EQ(ap::logText("\xE2\x82\xAC\xE2\x82\xAC\xE2\x82\xAC", 8),
            "\xE2\x82\xAC\xE2\x82\xAC...(9 bytes)");
  // Whole characters below the limit are kept as they are.
  EXPECT_EQ(ap::logText("caf\xC3\xA9"), "caf\xC3\xA9");
}

// noteText (src/ros/note_text.cpp) and the input lines (src/ros/input_text.cpp): the texts as
// docs/node.md gives them, each with the counter of its own kind, one throttle per kind.
namespace {

/// Counters that tell every kind apart: each a different count.
ap::EngineCounters distinctCounters() {
  ap::EngineCounters c;
  c.gaps = 11;
  c.jumps_back = 12;
  c.rejected_future = 13;
  c.resets = 14;
  c.dropped_stale = 15;
  c.rejected_non_finite = 16;
  c.rejected_out_of_range = 17;
  c.failed_steps = 18;
  c.pending_overflow = 19;
  c.deferred_ticks = 20;
  c.rejected_no_rate = 21;
  c.rejected_covariance = 22;
  c.rejected_type = 23;
  c.dropped_no_tf = 24;
  c.rejected_bias = 25;
  c.held_ahead = 26;
  return c;
}

ap::EngineNote noteOf(ap::EngineNote::Kind kind) {
  ap::EngineNote note;
  note.kind = kind;
  note.source = ap::Source::Imu;
  note.stamp = 1500000000250000000LL;  // 1500000000.25 s
  return note;
}

std::string noteLine(ap::EngineNote::Kind kind, bool dynamic = false) {
  ap::Parameters p;
  p.max_dt = 0.25;
  p.max_future = 2.5;
  return ap::noteText(noteOf(kind), distinctCounters(), p, dynamic).text;
}

constexpr ap::EngineNote::Kind kAllNotes[] = {
    ap::EngineNote::Gap,         ap::EngineNote::StampsJumpedBack,
    ap::EngineNote::Future,      ap::EngineNote::ClockJumpedBack,
    ap::EngineNote::Stale,       ap::EngineNote::NonFinite,
    ap::EngineNote::OutOfRange,  ap::EngineNote::FailedStep,
    ap::EngineNote::PendingFull, ap::EngineNote::Deferred,
    ap::EngineNote::HeldAhead,   ap::EngineNote::StampFilterMisfit};

}  // namespace

TEST(NoteText, EachKindCountsItsOwnCounter) {
  const std::string imu = "imu/data_raw";  // the topic the node subscribes (docs/node.md)
  EXPECT_EQ(noteLine(ap::EngineNote::Gap),
            imu +
                ": gap longer than max_dt = 0.25 s or 5.5 periods of the stream before "
                "1500000000.250000: not integrated across, state held (11 gaps so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::StampsJumpedBack),
            imu +
                ": stamps jumped back to 1500000000.250 and went on from there (looped bag, "
                "restarted driver?): reset to the initial state (12 jumps so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::Future),
            imu +
                ": stamp 1500000000.250000 more than max_future = 2.5 s ahead of ROS time: "
                "rejected (13 so far; unsynchronised clocks?)");
  EXPECT_EQ(noteLine(ap::EngineNote::ClockJumpedBack),
            "ROS time jumped back to 1500000000.250 s (looped bag or restarted clock): reset to "
            "the initial state (14 resets so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::Stale),
            imu + ": stamp 1500000000.250000 at or before the last one: dropped (15 so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::NonFinite),
            imu + ": NaN or infinite value or stamp: rejected (16 so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::OutOfRange),
            imu +
                ": value out of the accepted range (its energy or step would overflow): "
                "rejected (17 so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::FailedStep),
            imu +
                ": the integrator could not complete the step to 1500000000.250000: state "
                "held (18 failed so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::PendingFull),
            imu +
                ": more inputs stamped ahead of ROS time than the queue holds: the one "
                "stamped furthest ahead dropped (19 so far)");
  EXPECT_EQ(noteLine(ap::EngineNote::Deferred),
            "publishing fell behind ROS time at 1500000000.250 s: the rest of the grid follows "
            "on the next tick (20 so far)");
  // The misfit names the figures the filter measured and the bounds it judged them by.
  ap::EngineNote misfit = noteOf(ap::EngineNote::StampFilterMisfit);
  misfit.jitter = 0.0375;
  misfit.period = 0.02;
  EXPECT_EQ(ap::noteText(misfit, distinctCounters(), ap::Parameters{}, false).text,
            imu +
                ": the stamps do not fit one sensor period (stamp jitter 37.5 ms against a "
                "period of 20 ms, more than 0.25 periods): stamp_filter uses the receipt stamps "
                "until they fit again (below 0.1 periods); diagnostics stamp_filter_misfit");
  EXPECT_EQ(noteLine(ap::EngineNote::HeldAhead),
            imu +
                ": stamp 1500000000.250000 further ahead of ROS time than its stream by more "
                "than 1 s: dropped until 3 in a row confirm it (26 so far)");
}

TEST(NoteText, AJumpOfStampsSaysWhatTheModelDid) {
  EXPECT_NE(noteLine(ap::EngineNote::StampsJumpedBack, true)
                .find(": its inputs now act late, on ROS time (12 jumps so far)"),
            std::string::npos);
  EXPECT_NE(noteLine(ap::EngineNote::StampsJumpedBack, false)
                .find(": reset to the initial state (12 jumps so far)"),
            std::string::npos);
}

TEST(NoteText, TheClockIsNamedWhenNoSourceIs) {
  ap::EngineNote note = noteOf(ap::EngineNote::Gap);
  note.source.reset();
  EXPECT_EQ(ap::noteText(note, {}, ap::Parameters{}, false).text.rfind("ROS time: gap", 0), 0u);
}

TEST(NoteText, EveryKindHasAWarningAndAThrottleOfItsOwn) {
  std::set<std::string> kinds;
  for (ap::EngineNote::Kind kind : kAllNotes) {
    const ap::LogLine line = ap::noteText(noteOf(kind), {}, ap::Parameters{}, false);
    EXPECT_EQ(line.level, ros::console::levels::Warn);
    EXPECT_FALSE(line.kind.empty());
    kinds.insert(line.kind);
  }
  EXPECT_EQ(kinds.size(), std::size(kAllNotes));
}

namespace {

ap::InputDecoders decoders() {
  return ap::InputDecoders(ap::DecoderFrames::of(ap::validateParameters({})));
}

ap::Refusal refusalOf(ap::Refused why) {
  ap::Refusal r;
  r.why = why;
  r.frame = "imu_link";
  r.detail = "geometry_msgs/Pose";
  return r;
}

std::string refusalLine(ap::Refused why, const std::string& topic) {
  const ap::InputDecoders d = decoders();
  return ap::refusalText(refusalOf(why), topic, distinctCounters(), "base_link", d)->text;
}

}  // namespace

TEST(InputText, EachRefusalCountsItsOwnCounter) {
  EXPECT_EQ(refusalLine(ap::Refused::NoRate, "imu/data_raw"),
            "imu/data_raw: angular_velocity_covariance[0] == -1 (no rate, REP-145): rejected (21 "
            "so far)");
  ap::Refusal bad = refusalOf(ap::Refused::BadCovariance);
  bad.check = ap::RateCovarianceCheck::VarianceTooLarge;
  const ap::InputDecoders d = decoders();
  EXPECT_EQ(ap::refusalText(bad, "imu/data_raw", distinctCounters(), "base_link", d)->text,
            "imu/data_raw: angular_velocity_covariance rejected (" +
                std::string(ap::rateCovarianceCheckName(bad.check)) +
                "; accepted: symmetric, variances in [0, " +
                ap::formatted("%g", ap::kMaxRateVariance) + "] rad^2/s^2) (22 so far)");
  EXPECT_EQ(refusalLine(ap::Refused::NoTransform, "imu/data_raw"),
            "imu/data_raw: no transform from the rates' frame 'imu_link' to body_frame "
            "'base_link': publish the mount 'base_link' -> 'imu_link' on /tf_static, or take the "
            "IMU's own frame as the body: body_frame:=imu_link; dropped 24 messages so far "
            "(geometry_msgs/Pose)");
  ap::Refusal spaced = refusalOf(ap::Refused::NoTransform);
  spaced.frame = "imu link";
  spaced.detail = ap::kFrameIdRule;
  EXPECT_EQ(ap::refusalText(spaced, "imu/data_raw", distinctCounters(), "base_link", d)->text,
            "imu/data_raw: frame id 'imu link' refused; " + std::string(ap::kFrameIdRule));
  EXPECT_EQ(refusalLine(ap::Refused::NoTime, "body_twist"),
            "body_twist: unstamped message and no ROS time yet (/clock): dropped");
  EXPECT_EQ(refusalLine(ap::Refused::BiasFrame, "gyro_bias"),
            "gyro_bias: frame 'imu_link' rejected; accepted: 'base_link' (the body), the rate "
            "messages' frame once known, or empty (25 rejected so far)");
}

TEST(InputText, AWrongTypeNamesTheTypesOfItsOwnTopic) {
  EXPECT_EQ(refusalLine(ap::Refused::WrongType, "body_twist"),
            "body_twist: message type geometry_msgs/Pose rejected; the topic carries nothing yet "
            "(its first message's type; accepted: geometry_msgs/Twist or "
            "geometry_msgs/TwistStamped) (23 rejected so far)");
  EXPECT_EQ(refusalLine(ap::Refused::WrongType, "torque"),
            "torque: message type geometry_msgs/Pose rejected; the topic carries nothing yet (its "
            "first message's type; accepted: geometry_msgs/Wrench or geometry_msgs/WrenchStamped) "
            "(23 rejected so far)");
}

TEST(InputText, ATorqueWithoutItsTransformIsWarnedApartFromRates) {
  const ap::InputDecoders d = decoders();
  const ap::Refusal r = refusalOf(ap::Refused::NoTransform);
  const auto torque = ap::refusalText(r, "torque", distinctCounters(), "base_link", d);
  const auto rates = ap::refusalText(r, "body_twist", distinctCounters(), "base_link", d);
  EXPECT_EQ(torque->text,
            "torque in frame 'imu_link': no transform to 'base_link' yet: dropped "
            "(geometry_msgs/Pose)");
  EXPECT_NE(torque->kind, rates->kind);
}

TEST(InputText, EveryRefusalKindHasAThrottleOfItsOwn) {
  const ap::InputDecoders d = decoders();
  std::set<std::string> kinds;
  for (ap::Refused why : {ap::Refused::NoRate, ap::Refused::BadCovariance, ap::Refused::WrongType,
                          ap::Refused::NoTransform, ap::Refused::NoTime, ap::Refused::BiasFrame}) {
    const auto line = ap::refusalText(refusalOf(why), "imu/data_raw", {}, "base_link", d);
    ASSERT_TRUE(line);
    EXPECT_EQ(line->level, ros::console::levels::Warn);
    kinds.insert(line->kind);
  }
  kinds.insert(ap::biasRejectedText({}).kind);
  EXPECT_EQ(kinds.size(), 7u);
}

TEST(InputText, AFixWithoutOrientationIsLeftToTheFixInput) {
  const ap::InputDecoders d = decoders();
  EXPECT_FALSE(ap::refusalText(refusalOf(ap::Refused::NoOrientation), "orientation_fix", {},
                               "base_link", d));
}

TEST(InputText, TheMountAndARejectedBias) {
  const Eigen::Quaterniond q(0.5, 0.5, -0.5, 0.5);  // w x y z
  EXPECT_EQ(ap::mountText("imu\nlink", "base_link", q),
            "rates in frame 'imu?link' are rotated into 'base_link' by q = [0.5, -0.5, 0.5, 0.5] "
            "(x y z w)");
  EXPECT_EQ(ap::biasRejectedText(distinctCounters()).text,
            "gyro_bias: non-finite or larger than " + ap::formatted("%g", ap::kMaxBodyRate) +
                " rad/s: rejected (25 so far)");
}
