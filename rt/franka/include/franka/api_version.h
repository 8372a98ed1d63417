// Which libfranka API version the franka headers present (docs/franka_api.md):
//   1500 (default): libfranka 0.15, the current one (FR3 and Panda owners on recent system images);
//   900: libfranka 0.9, the one Panda (FER) owners still run: its limitRate signatures and rate
//        limits (franka/rate_limiting.h) and limit_rate = true by default in Robot::control.
// Choose with a compile definition, e.g. target_compile_definitions(app PRIVATE CSP_FRANKA_API_VERSION=900).
// The library holds the functions of both, so one installed CSP serves programs of either.
#pragma once

#ifndef CSP_FRANKA_API_VERSION
#define CSP_FRANKA_API_VERSION 1500
#endif

#if CSP_FRANKA_API_VERSION != 1500 && CSP_FRANKA_API_VERSION != 900
#error "CSP_FRANKA_API_VERSION must be 1500 (libfranka 0.15) or 900 (libfranka 0.9)"
#endif

namespace franka {
namespace detail {
// Robot::control's default for limit_rate: libfranka 0.9 limited by default, 0.15 does not.
constexpr bool kDefaultLimitRate = CSP_FRANKA_API_VERSION < 1000;
}  // namespace detail
}  // namespace franka
