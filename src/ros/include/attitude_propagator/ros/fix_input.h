// The orientation_fix topic in the node: each message decoded by the message layer's FixDecoder
// (fix_decoder.h), handed to AttitudeEngine::submitFix, and what became of it logged (throttled,
// by name) and shown in diagnostics. The rules live in the decoder and the engine; this only
// wires them to ROS, beside the wrapper (attitude_propagator_ros.h), on its callback queue.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/time.h>
#include <topic_tools/shape_shifter.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/ros/instance_log.h"

namespace attitude_propagator {

/// Fixes not applied in a row (refused, rejected, too old ...) from which diagnostics WARN: the
/// output is not corrected as the user thinks.
constexpr std::uint64_t kFixWarnRun = 3;

class FixInput {
 public:
  /// Logs through the wrapper's `log` (in the instance's name, throttled per kind).
  FixInput(const NodeConfig& config, InstanceLog& log);

  /// Decodes one message (`frames` is asked for the header frame and fix_frame's mount),
  /// submits the fix, and logs a refusal or an outcome other than applied or waiting. The
  /// messages of `publisher` lost before it (its header.seq's gap: SequenceGaps) are counted
  /// (fixes_lost) and warned about.
  void onMessage(const topic_tools::ShapeShifter& msg, const ros::Time& arrival,
                 const std::string& publisher, AttitudeEngine& engine, FrameSource& frames);
  /// A fix has needed tf: the node keeps its listener.
  bool usesTf() const { return uses_tf_; }
  /// Fixes refused or not applied since the last one applied (counted from the counters, so a
  /// fix that waited counts when the rates reach it).
  std::uint64_t notAppliedInARow(const EngineCounters& c);
  /// The WARN summary when kFixWarnRun or more fixes in a row were not applied; else empty.
  std::string warning(const EngineCounters& c);
  /// The decoder's refusals, the fixes pending and lost, and with estimate_gyro_bias the
  /// estimate and its standard deviation (the engine's fix counters are the node's, from the
  /// core's table).
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status,
                const AttitudeEngine& engine) const;

  /// Asks the master which type is registered on the fix topic (`topic`, resolved): another
  /// publisher's type than the topic's never reaches the node (ROS 1 refuses its connection),
  /// so it is said once per type (a warning, and `fixes_other_type` in the diagnostics). One
  /// call to the master: the wrapper calls it every kFixTypeCheckPeriod.
  void checkRegisteredType(const std::string& topic);

 private:
  /// Every fix not applied so far: the engine's refusals and the decoder's.
  std::uint64_t notApplied(const EngineCounters& c) const;
  void logRefusal(const Refusal& r);
  void logOutcome(FixOutcome outcome, Stamp stamp, const AttitudeEngine& engine);
  /// A warning of `kind`, throttled per kind (kFixWarnPeriod).
  void warn(const char* kind, const std::string& text);

  FixDecoder decoder_;
  SequenceGaps gaps_;  // fixes lost before the node (the subscriber queue, the transport)
  std::vector<std::uint8_t> buffer_;  // a message's bytes, for its header.seq
  FixConfig config_;
  bool uses_tf_ = false;
  std::uint64_t applied_seen_ = 0;               // fixes_accepted when last looked at
  std::uint64_t not_applied_at_last_apply_ = 0;  // notApplied() then
  std::string last_reason_;                      // the latest refusal or rejection, by name
  std::string other_type_;                       // another type registered on the topic
  InstanceLog& log_;
};

}  // namespace attitude_propagator
