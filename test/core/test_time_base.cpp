// TimeBase (time/time_base.h, docs/design.md §6.1): core time is seconds since an origin, the
// whole second of the stamp that pinned it; the engine pins it where time starts, moves it to a
// state held far away and forgets it when time starts again.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/time/time_base.h"
#include "engine_fixtures.h"

namespace ap = attitude_propagator;
using engine_fixtures::at;

namespace {

constexpr ap::Stamp kSecond = 1000000000;

TEST(TimeBase, TheOriginIsTheWholeSecondOfTheFirstStampPinnedAndStays) {
  ap::TimeBase time;
  EXPECT_FALSE(time.pinned());
  EXPECT_FALSE(time.stampAt(0.0));
  time.pin(12 * kSecond + 345678901);
  EXPECT_TRUE(time.pinned());
  EXPECT_EQ(time.stampAt(0.0), std::optional<ap::Stamp>(12 * kSecond));
  time.pin(40 * kSecond);  // pinned already: stays
  EXPECT_EQ(time.coreTime(13 * kSecond + 500000000), 1.5);
  EXPECT_EQ(time.stampAt(1.5), std::optional<ap::Stamp>(13 * kSecond + 500000000));
  time.rebase(40 * kSecond + 1);
  EXPECT_EQ(time.coreTime(40 * kSecond + 1), 1e-9);
  time.forget();
  EXPECT_FALSE(time.pinned());
  time.pin(7 * kSecond);
  EXPECT_EQ(time.coreTime(7 * kSecond), 0.0);
}

TEST(TimeBase, AStampIsFarAtKFarFromOriginSecondsNotBefore) {
  ap::TimeBase time;
  time.pin(100 * kSecond);
  const auto far = static_cast<ap::Stamp>(ap::kFarFromOrigin) * kSecond;
  EXPECT_FALSE(time.isFar(100 * kSecond + far - 1));
  EXPECT_TRUE(time.isFar(100 * kSecond + far));
  EXPECT_TRUE(time.isFar(100 * kSecond + far + 1));
  EXPECT_TRUE(time.isFar(100 * kSecond - far));
}

// The engine pins the origin at the first input the model takes; in the dynamic model with no
// input, at the first grid stamp it publishes (the newest at or before the clock), which at
// 7.5 Hz lies in the second before the clock's: 10.933 s for a clock at 11.05 s.
TEST(TimeBase, TheEnginePinsItAtTheFirstInputOrTheFirstGridStamp) {
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine kinematic(engine_fixtures::kinematicConfig(), sink);
  kinematic.clockTick(at(20.5));  // the kinematic model publishes nothing from the clock
  EXPECT_FALSE(kinematic.timeBase().pinned());
  kinematic.submit(engine_fixtures::rate(at(21.25), Eigen::Vector3d::Zero()));
  EXPECT_EQ(kinematic.timeBase().stampAt(0.0), std::optional<ap::Stamp>(at(21.0)));

  ap::EngineConfig c = engine_fixtures::spinningSphereConfig();
  c.publish_rate = 7.5;
  ap::AttitudeEngine dynamic(c, sink);
  dynamic.clockTick(at(11.05));
  EXPECT_EQ(dynamic.timeBase().stampAt(0.0), std::optional<ap::Stamp>(at(10.0)));
}

}  // namespace
