#include "attitude_propagator/estimation/replay_budget.h"

#include <algorithm>

namespace attitude_propagator {

namespace {

constexpr Stamp kSecond = 1000000000;

/// The whole second a stamp falls in (floor, also before the epoch).
Stamp secondOf(Stamp stamp) { return stamp >= 0 ? stamp / kSecond : -((-stamp - 1) / kSecond) - 1; }

}  // namespace

void ReplayBudget::roll(Stamp stamp) {
  const Stamp second = secondOf(stamp);
  if (started_ && second <= second_) return;  // this second, or an earlier one: counted here
  recorded_before_ = started_ && second == second_ + 1 ? recorded_ : 0;
  recorded_ = 0;
  replayed_ = 0;
  second_ = second;
  started_ = true;
}

void ReplayBudget::recorded(Stamp stamp) {
  roll(stamp);
  ++recorded_;
}

std::size_t ReplayBudget::allowance() const {
  return kReplayFloor + kReplayPerRecorded * std::max(recorded_, recorded_before_);
}

bool ReplayBudget::affords(Stamp stamp, std::size_t states) {
  roll(stamp);
  return replayed_ + states <= allowance();
}

void ReplayBudget::charge(Stamp stamp, std::size_t states) {
  roll(stamp);
  replayed_ += states;
}

}  // namespace attitude_propagator
