// TfConflictWatch (src/ros/tf_conflict_watch.cpp) against its documented rules (docs/node.md,
// tf_conflict): a frame has one parent; `warn` names the first conflict, `stop` stops our tf at
// each conflict and names it; a stop from /tf resumes after kTfConflictClearance of wall time
// without another parent, one from /tf_static only when publish_tf is switched off and on.
#include <cstdint>
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/ros/tf_conflict_watch.h"

namespace ap = attitude_propagator;

namespace {

ap::Parameters params(const std::string& mode, bool reverse_tf = false) {
  ap::Parameters p;
  p.fixed_frame = "odom";
  p.body_frame = "base_link";
  p.tf_conflict = mode;
  p.reverse_tf = reverse_tf;
  return p;
}

tf2_msgs::TFMessage edge(const std::string& parent, const std::string& child) {
  tf2_msgs::TFMessage msg;
  msg.transforms.resize(2);
  msg.transforms[0].header.frame_id = "map";
  msg.transforms[0].child_frame_id = "other";
  msg.transforms[1].header.frame_id = parent;
  msg.transforms[1].child_frame_id = child;
  return msg;
}

ros::WallTime at(double s) { return ros::WallTime(1000.0 + s); }

}  // namespace

TEST(TfConflictWatch, AnotherParentOfOurChildIsAConflict) {
  ap::TfConflictWatch watch;
  const auto line = watch.onTfSeen(edge("map", "base_link"), "/robot_state_publisher", false, false,
                                   params("warn"), at(0));
  ASSERT_TRUE(line);
  EXPECT_EQ(line->level, ros::console::levels::Warn);
  EXPECT_EQ(line->text,
            "tf: /robot_state_publisher also publishes 'base_link' as the child of 'map' on /tf "
            "(we publish odom -> base_link): a frame has one parent. Publish our transform to a "
            "frame of its own (body_frame:=base_link_attitude), or reverse_tf:=true for a tree "
            "rooted at the body, or publish_tf:=false; tf_conflict:=stop would stop our tf "
            "instead");
  EXPECT_EQ(watch.conflicts(), 1u);
  EXPECT_FALSE(watch.stopped());  // warn never stops
}

TEST(TfConflictWatch, OurParentAsAChildIsNone) {
  ap::TfConflictWatch watch;
  EXPECT_FALSE(watch.onTfSeen(edge("map", "odom"), "/a", false, false, params("stop"), at(0)));
  EXPECT_EQ(watch.conflicts(), 0u);
  EXPECT_FALSE(watch.stopped());
}

TEST(TfConflictWatch, ReverseTfMakesTheFixedFrameOurChild) {
  ap::TfConflictWatch watch;
  EXPECT_FALSE(
      watch.onTfSeen(edge("map", "base_link"), "/a", false, false, params("stop", true), at(0)));
  const auto line =
      watch.onTfSeen(edge("map", "odom"), "/a", false, false, params("stop", true), at(0));
  ASSERT_TRUE(line);
  EXPECT_NE(line->text.find("also publishes 'odom' as the child of 'map' on /tf (we publish "
                            "base_link -> odom)"),
            std::string::npos);
  EXPECT_TRUE(watch.stopped());
}

TEST(TfConflictWatch, WarnNamesOnlyTheFirstConflict) {
  ap::TfConflictWatch watch;
  EXPECT_TRUE(watch.onTfSeen(edge("map", "base_link"), "/a", false, false, params("warn"), at(0)));
  EXPECT_FALSE(watch.onTfSeen(edge("map", "base_link"), "/a", false, false, params("warn"), at(1)));
  EXPECT_FALSE(watch.onTfSeen(edge("map", "base_link"), "/a", false, true, params("warn"), at(2)));
  EXPECT_EQ(watch.conflicts(), 3u);
}

TEST(TfConflictWatch, StopNamesEachStop) {
  ap::TfConflictWatch watch;
  const ap::Parameters p = params("stop");
  const auto first = watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(0));
  ASSERT_TRUE(first);
  EXPECT_NE(first->text.find("; tf_conflict is stop: no tf from this node until no other parent "
                             "has been seen on /tf for 2 s, or publish_tf is switched off and on"),
            std::string::npos);
  EXPECT_TRUE(watch.stopped());
  EXPECT_FALSE(watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(0.5)));  // still
  EXPECT_TRUE(watch.resumeTfIfClear(p, at(0.5 + ap::kTfConflictClearance)));
  EXPECT_TRUE(watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(10)));  // again
  EXPECT_EQ(watch.conflicts(), 3u);
  EXPECT_EQ(watch.resumes(), 1u);
}

TEST(TfConflictWatch, AStopFromTfResumesAfterTheClearanceAndNotBefore) {
  ap::TfConflictWatch watch;
  const ap::Parameters p = params("stop");
  watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(0));
  watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(1));  // the latest conflict
  EXPECT_FALSE(watch.resumeTfIfClear(p, at(1 + ap::kTfConflictClearance - 1e-3)));
  EXPECT_TRUE(watch.stopped());
  const auto line = watch.resumeTfIfClear(p, at(1 + ap::kTfConflictClearance));
  ASSERT_TRUE(line);
  EXPECT_EQ(line->level, ros::console::levels::Info);
  EXPECT_EQ(line->text, "tf: no other parent on /tf for 2 s: publishing odom -> base_link again");
  EXPECT_FALSE(watch.stopped());
  EXPECT_EQ(watch.resumes(), 1u);
  EXPECT_FALSE(watch.resumeTfIfClear(p, at(100)));  // nothing to resume
  EXPECT_EQ(watch.resumes(), 1u);
}

TEST(TfConflictWatch, AStopFromTfStaticWaitsForAToggle) {
  ap::TfConflictWatch watch;
  const ap::Parameters p = params("stop");
  const auto line = watch.onTfSeen(edge("map", "base_link"), "/static", false, true, p, at(0));
  ASSERT_TRUE(line);
  EXPECT_NE(line->text.find("on /tf_static (we publish"), std::string::npos);
  EXPECT_NE(line->text.find("; tf_conflict is stop: no tf from this node until publish_tf is "
                            "switched off and on"),
            std::string::npos);
  EXPECT_FALSE(watch.resumeTfIfClear(p, at(1000)));
  EXPECT_TRUE(watch.stopped());
  const auto resumed = watch.resumeTf("publish_tf switched off and on", p);
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->text,
            "tf: publish_tf switched off and on: publishing odom -> base_link again");
  EXPECT_FALSE(watch.stopped());
  // The toggle cleared the static stop: a later stop from /tf clears with time again.
  watch.onTfSeen(edge("map", "base_link"), "/a", false, false, p, at(2000));
  EXPECT_TRUE(watch.resumeTfIfClear(p, at(2000 + ap::kTfConflictClearance)));
}

TEST(TfConflictWatch, AToggleResumesOnceAndANewStaticParentStopsAgain) {
  ap::TfConflictWatch watch;
  const ap::Parameters p = params("stop");
  watch.onTfSeen(edge("map", "base_link"), "/static", false, true, p, at(0));
  watch.resumeTf("publish_tf switched off and on", p);
  // A latched parent seen, then a /tf parent: the stop comes from /tf_static again.
  watch.onTfSeen(edge("map", "base_link"), "/static", false, true, p, at(1));
  EXPECT_FALSE(watch.resumeTfIfClear(p, at(1000)));
  EXPECT_EQ(watch.resumes(), 1u);
  ap::TfConflictWatch idle;
  EXPECT_FALSE(idle.resumeTf("reverse_tf changed our child frame", p));
  EXPECT_EQ(idle.resumes(), 0u);
}

TEST(TfConflictWatch, ThePublisherAndParentAreCutForTheLog) {
  ap::TfConflictWatch watch;
  const auto line = watch.onTfSeen(edge("a\nb", "base_link"), std::string(1000, 'n'), false, false,
                                   params("warn"), at(0));
  ASSERT_TRUE(line);
  EXPECT_NE(line->text.find("...(1000 bytes) also publishes"), std::string::npos);
  EXPECT_NE(line->text.find("the child of 'a?b'"), std::string::npos);
}

// In a nodelet manager every nodelet publishes under the manager's node name: the watch tells
// our transforms (our edge at a stamp we sent) from a sibling's.
namespace {

tf2_msgs::TFMessage stamped(const std::string& parent, const std::string& child, double t) {
  tf2_msgs::TFMessage msg = edge(parent, child);
  msg.transforms[1].header.stamp = ros::Time(t);
  return msg;
}

void send(ap::TfConflictWatch& watch, double t) {
  watch.sent(stamped("odom", "base_link", t).transforms[1]);
}

}  // namespace

TEST(TfConflictWatch, InAManagerOurOwnTransformIsNoConflict) {
  ap::TfConflictWatch watch;
  send(watch, 1.0);
  send(watch, 1.01);
  EXPECT_FALSE(watch.onTfSeen(stamped("odom", "base_link", 1.0), "/manager", true, false,
                              params("warn"), at(0)));
  EXPECT_FALSE(watch.onTfSeen(stamped("odom", "base_link", 1.01), "/manager", true, false,
                              params("warn"), at(0)));
  EXPECT_EQ(watch.conflicts(), 0u);
}

TEST(TfConflictWatch, InAManagerASiblingsOtherParentIsAConflictNamedAsSuch) {
  ap::TfConflictWatch watch;
  send(watch, 1.0);
  // The same stamp as one of ours, under another parent: a sibling nodelet's.
  const auto line = watch.onTfSeen(stamped("map", "base_link", 1.0), "/manager", true, false,
                                   params("warn"), at(0));
  ASSERT_TRUE(line);
  EXPECT_EQ(watch.conflicts(), 1u);
  EXPECT_NE(line->text.find("another nodelet in manager /manager also publishes 'base_link' as "
                            "the child of 'map'"),
            std::string::npos)
      << line->text;
}

TEST(TfConflictWatch, InAManagerOurEdgeAtAStampWeDidNotSendIsASiblings) {
  ap::TfConflictWatch watch;
  send(watch, 1.0);
  EXPECT_TRUE(watch.onTfSeen(stamped("odom", "base_link", 1.005), "/manager", true, false,
                             params("warn"), at(0)));
  EXPECT_EQ(watch.conflicts(), 1u);
}

TEST(TfConflictWatch, InAManagerASiblingsStaticParentIsAConflict) {
  ap::TfConflictWatch watch;
  send(watch, 1.0);
  // We never publish our edge on /tf_static: there it is a sibling's, whatever its stamp.
  EXPECT_TRUE(watch.onTfSeen(stamped("odom", "base_link", 1.0), "/manager", true, true,
                             params("warn"), at(0)));
}

TEST(TfConflictWatch, TheNewestOwnStampsAreKeptAndNoMore) {
  // Stamps 1 .. kOwnStampsKept + 1 ns after 1 s: the first is forgotten, the second kept.
  ap::TfConflictWatch fresh;
  const auto at_ns = [](std::uint64_t ns) {
    tf2_msgs::TFMessage msg = edge("odom", "base_link");
    msg.transforms[1].header.stamp.fromNSec(1000000000ull + ns);
    return msg;
  };
  for (std::uint64_t ns = 1; ns <= ap::kOwnStampsKept + 1; ++ns) {
    fresh.sent(at_ns(ns).transforms[1]);
  }
  EXPECT_FALSE(fresh.onTfSeen(at_ns(ap::kOwnStampsKept + 1), "/m", true, false, params("warn"),
                              at(0)));                                               // the newest
  EXPECT_FALSE(fresh.onTfSeen(at_ns(2), "/m", true, false, params("warn"), at(0)));  // kept
  EXPECT_EQ(fresh.conflicts(), 0u);
  EXPECT_TRUE(fresh.onTfSeen(at_ns(1), "/m", true, false, params("warn"), at(0)));  // forgotten
  EXPECT_EQ(fresh.conflicts(), 1u);
}

TEST(TfConflictWatch, AnotherNodesEdgeAtOurStampIsStillAConflict) {
  ap::TfConflictWatch watch;
  send(watch, 1.0);
  // Not named like us: another node, whatever the stamp.
  EXPECT_TRUE(watch.onTfSeen(stamped("odom", "base_link", 1.0), "/other", false, false,
                             params("warn"), at(0)));
}
