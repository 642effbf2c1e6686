// logText (src/ros/log_text.cpp): what a message's string becomes in a log line.
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/ros/log_text.h"

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
