// The bounds and periods of the node's wiring: the size of each queue it sets, how often it
// looks at the clock, how often a warning about input that keeps coming bad is repeated.
#pragma once

#include <cstdint>

namespace attitude_propagator {

// Every queue the node sets is bounded in messages: at most the queue size times the size of
// one message, per queue. The streamed inputs' and the outputs' sizes are parameters
// (`input_queue_size`, `output_queue_size`, docs/parameters.md); their defaults:
// - inputs are queued, not dropped, through a burst of 10 000 messages (a bag played fast, a
//   load generator); beyond it roscpp drops the oldest;
// - 5 000 per subscriber connection and output: a burst of a few thousand reaches a subscriber
//   that keeps reading (kinematic.test sends 3000 to a Python subscriber; with 1000 it lost
//   some), while one that falls further behind (a slow remote reader) loses the oldest. One
//   slow subscriber of all three outputs held the node at 82 MB with 10 000 (IMU input at
//   31 kHz), at 31 MB with 5 000. Subscribers in the same nodelet manager are served through
//   their own queue.
// roscpp's own hand-over from publish() to its I/O thread has no bound: the node bounds what it
// hands over between two rounds of that thread to the same size per output (hand_over_bound.h).
// The tf watch needs one message of a conflicting publisher, not every transform on /tf.
constexpr std::uint32_t kTfWatchQueueSize = 1000;
// Topics with a message now and then (gyro bias, /tf_static).
constexpr std::uint32_t kSparseQueueSize = 100;
// How often (wall s) the master is asked which type is registered on the fix topic: one
// XML-RPC call, about a millisecond on the callback thread.
constexpr double kFixTypeCheckPeriod = 5.0;
// Throttle period (s) of warnings about input that keeps coming bad.
constexpr double kWarnPeriod = 5.0;
// How often the clock is looked at while nothing else happens (wall seconds): publishes a
// grid stamp the timer missed, notices a clock that went back, updates diagnostics.
constexpr double kWatchdogPeriod = 0.1;

}  // namespace attitude_propagator
