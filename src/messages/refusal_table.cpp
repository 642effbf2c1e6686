#include "attitude_propagator/messages/refusal_table.h"

#include <cstring>
#include <stdexcept>

namespace attitude_propagator {

const std::vector<RefusalRow>& refusalTable() {
  using F = FixRefusals;
  static const std::vector<RefusalRow> table = {
      {Refused::NoRate, Rejection::NoRate, false, "rejected_no_rate", nullptr, nullptr},
      {Refused::BadCovariance, Rejection::BadCovariance, false, "rejected_covariance", nullptr,
       nullptr},
      {Refused::WrongType, Rejection::WrongType, false, "rejected_type", "fixes_refused_type",
       &F::type},
      {Refused::NoTransform, Rejection::NoTransform, false, "dropped_no_tf", "fixes_refused_no_tf",
       &F::no_tf},
      {Refused::NoTime, Rejection::NoTime, false, "dropped_no_time", "fixes_refused_no_time",
       &F::no_time},
      {Refused::BiasFrame, std::nullopt, true, "rejected_bias", nullptr, nullptr},
      {Refused::NoOrientation, std::nullopt, false, nullptr, "fixes_refused_no_orientation",
       &F::no_orientation},
      {Refused::FixBodyFrame, std::nullopt, false, nullptr, "fixes_refused_body_frame",
       &F::body_frame},
  };
  return table;
}

const RefusalRow& refusalRow(Refused why) {
  for (const RefusalRow& row : refusalTable()) {
    if (row.why == why) return row;
  }
  throw std::logic_error("refusalRow: a Refused without a row");
}

std::string fixRefusalCounts(const FixRefusals& refusals) {
  static const std::size_t prefix = std::strlen("fixes_refused_");
  std::string out;
  for (const RefusalRow& row : refusalTable()) {
    if (!row.fix_counter) continue;
    out += (out.empty() ? "" : ", ") + std::string(row.fix_counter + prefix) + " " +
           std::to_string(refusals.*row.fix_count);
  }
  return out;
}

}  // namespace attitude_propagator
