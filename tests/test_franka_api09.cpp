// libfranka 0.9's API (CSP_FRANKA_API_VERSION=900, set for this file in tests/CMakeLists.txt):
// its limitRate signatures (a symmetric max_velocity), its Panda rate limits and limit_rate = true
// by default, from the same library as the 0.15 API (docs/franka_api.md).
#include <gtest/gtest.h>

#include <array>

#include "franka/log.h"
#include "franka/rate_limiting.h"
#include "franka/robot.h"

static_assert(CSP_FRANKA_API_VERSION == 900, "this file tests the libfranka 0.9 API");

namespace {

TEST(FrankaApi09, PandaLimitsAndSymmetricVelocityLimits) {
  // libfranka 0.9's values: 2.175 rad/s less the margins for 3 lost packets at 15 rad/s^2.
  EXPECT_DOUBLE_EQ(franka::kMaxJointVelocity[0], 2.175 - 1e-3 - 3.0 * 1e-3 * (15.0 - 1e-3));
  EXPECT_DOUBLE_EQ(franka::kMaxTranslationalVelocity, 2.0 - 1e-3 - 3.0 * 1e-3 * (13.0 - 1e-3));
  EXPECT_TRUE(franka::detail::kDefaultLimitRate);
  // A velocity command far below -max is held by the same bounds as one far above +max.
  const double up = franka::limitRate(1.0, 10.0, 5000.0, 5.0, 0.999, 0.0);
  const double down = franka::limitRate(1.0, 10.0, 5000.0, -5.0, -0.999, 0.0);
  EXPECT_NEAR(up, -down, 1e-15);
  EXPECT_LE(up, 1.0);
  // Seven joint positions: the implied velocity is limited by the jerk from rest.
  std::array<double, 7> target{}, zero{};
  target.fill(1.0);
  const auto q = franka::limitRate(franka::kMaxJointVelocity, franka::kMaxJointAcceleration, franka::kMaxJointJerk,
                                   target, zero, zero, zero);
  for (std::size_t i = 0; i < 7; ++i) EXPECT_NEAR(q[i], franka::kMaxJointJerk[i] * 1e-9, 1e-15);
  // franka/log.h, 0.9's home of Record.
  franka::Record record;
  EXPECT_EQ(record.command.torques.tau_J, zero);
}

}  // namespace
