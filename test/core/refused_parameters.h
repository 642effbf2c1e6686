// The assertion the parameter tests share: validateParameters refuses a value with one message
// that starts with the parameter's name and lists what it accepts.
#pragma once

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"

/// Expects `p` refused for `name`; with `accepted`, the message must list exactly those values
/// ("accepted: <accepted>"), otherwise just say what is accepted.
inline void expectRefused(const attitude_propagator::Parameters& p, const std::string& name,
                          const std::string& accepted = "") {
  try {
    attitude_propagator::validateParameters(p);
    ADD_FAILURE() << "accepted a bad " << name;
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(name + ": ", 0), 0u) << message;
    EXPECT_NE(message.find("accepted" + (accepted.empty() ? "" : ": " + accepted)),
              std::string::npos)
        << message;
  }
}
