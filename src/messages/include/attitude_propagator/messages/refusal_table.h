// What each refusal of the message layer counts, in one table: the engine's counter for an input
// (a rate, torque, bias or field sample) and the fix input's counter for a fix. The decoders,
// the node's diagnostics and the tools' summaries read it; docs/node.md names the same counters.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/input_decoders.h"

namespace attitude_propagator {

struct RefusalRow {
  Refused why;
  /// The engine's count of an input refused so (AttitudeEngine::reject); empty: not one.
  std::optional<Rejection> rejection;
  /// A bias sample refused so is counted by AttitudeEngine::rejectBias (rejected_bias).
  bool bias = false;
  /// The engine's counter named for an input refused so; nullptr: a fix's refusal only.
  const char* input_counter = nullptr;
  /// The fix input's counter, and where FixRefusals counts it; nullptr: not a fix's refusal.
  const char* fix_counter = nullptr;
  std::uint64_t FixRefusals::*fix_count = nullptr;
};

/// Every Refused once, in the enum's order.
const std::vector<RefusalRow>& refusalTable();
const RefusalRow& refusalRow(Refused why);

/// A fix input's refusals as the tools' summaries give them: each fix counter of the table in
/// its order, by its name without `fixes_refused_`: "type 0, no_tf 1, no_time 0, ...".
std::string fixRefusalCounts(const FixRefusals& refusals);

}  // namespace attitude_propagator
