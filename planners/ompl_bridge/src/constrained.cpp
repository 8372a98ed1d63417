// plan_on_manifold: written by the constrained-task work (helper h-task replaces this file).
#include <stdexcept>

#include "ompl_common.hpp"

namespace csp::planners::ompl_bridge {

Result plan_on_manifold(const Request&, const Callbacks&, const ManifoldConstraint&) {
  throw std::logic_error("plan_on_manifold: not built yet");
}

}  // namespace csp::planners::ompl_bridge
