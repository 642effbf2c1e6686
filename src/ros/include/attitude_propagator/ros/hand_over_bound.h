// The node's bound on what it hands to roscpp. publish() puts a serialized message in the
// publisher's hand-over queue, which roscpp's one I/O thread empties into each subscriber's
// bounded queue once per round of its loop. While that thread is kept reading an input faster
// than it can (an IMU at 100 kHz), it does not come round, the hand-over queue has no bound,
// and what the node publishes meanwhile piles up (hundreds of MB). So the node counts what it
// hands over since the I/O thread last came round, and past `output_queue_size` messages per
// output it drops the newest and counts it: the hand-over holds at most that many per output,
// whatever the input rate. The I/O thread's rounds are seen through roscpp's poll-thread
// listener (PollManager::addPollThreadListener), which it calls once per round, just before it
// empties the hand-over queues.
#pragma once

#include <atomic>
#include <cstdint>

#include <boost/signals2/connection.hpp>

namespace attitude_propagator {

/// The I/O thread's rounds: bumped from that thread, read from the callback thread.
class IoRounds {
 public:
  void ranOnce() { rounds_.fetch_add(1, std::memory_order_relaxed); }
  std::uint64_t count() const { return rounds_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> rounds_{0};
};

/// roscpp's poll-thread listener that counts the rounds, for as long as it lives: removed when
/// its owner goes, also when the owner's constructor throws after it was added (a nodelet that
/// refuses to start must leave nothing behind that the I/O thread calls).
class IoRoundsListener {
 public:
  explicit IoRoundsListener(IoRounds& rounds);
  ~IoRoundsListener();
  IoRoundsListener(const IoRoundsListener&) = delete;
  IoRoundsListener& operator=(const IoRoundsListener&) = delete;

 private:
  boost::signals2::connection connection_;
};

/// One output's bound (its publisher), used from the callback thread only.
class HandOverBound {
 public:
  HandOverBound(const IoRounds& rounds, std::uint64_t limit) : rounds_(rounds), limit_(limit) {}

  /// Whether one more message may be handed over now: counted as handed over, or dropped.
  bool admit() {
    const std::uint64_t round = rounds_.count();
    if (round != seen_round_) {
      seen_round_ = round;
      handed_ = 0;  // what was handed over before is on its way to the subscribers' queues
    }
    if (handed_ >= limit_) {
      ++dropped_;
      return false;
    }
    ++handed_;
    return true;
  }
  std::uint64_t dropped() const { return dropped_; }

 private:
  const IoRounds& rounds_;
  std::uint64_t limit_;
  std::uint64_t seen_round_ = 0;
  std::uint64_t handed_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace attitude_propagator
