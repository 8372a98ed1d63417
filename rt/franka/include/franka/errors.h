// franka::Errors: CSP's error flags with libfranka 0.15's accessors, e.g. errors.joint_reflex().
#pragma once

#include "csp/rt/errors.hpp"

namespace franka {

using Errors = csp::rt::Errors;

}  // namespace franka
