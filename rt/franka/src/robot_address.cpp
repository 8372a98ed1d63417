#include "robot_address.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>

namespace csp::franka_address {
namespace {

bool ends_with(const std::string& text, const std::string& tail) {
  return text.size() >= tail.size() && text.compare(text.size() - tail.size(), tail.size(), tail) == 0;
}

bool looks_like_scenario_path(const std::string& address) {
  return ends_with(address, ".yaml") || ends_with(address, ".yml") || std::filesystem::is_regular_file(address);
}

// An IPv4/IPv6 address or a hostname (RFC 1123 labels): letters, digits, '-', '.', and ':' for IPv6.
bool is_host(const std::string& address) {
  return std::all_of(address.begin(), address.end(), [](unsigned char c) {
    return std::isalnum(c) != 0 || c == '-' || c == '.' || c == ':' || c == '_';
  });
}

}  // namespace

std::string scenario_for_address(const std::string& franka_address, const char* scenario_env,
                                 const std::string& shipped_dir) {
  if (franka_address.empty()) throw std::invalid_argument("the robot's address is empty");
  if (looks_like_scenario_path(franka_address)) return franka_address;
  if (!is_host(franka_address))
    throw std::invalid_argument("`" + franka_address +
                                "` is neither a scenario file nor an IP address or hostname");
  const std::string chosen = scenario_env && *scenario_env ? scenario_env : "libfranka_panda";
  if (looks_like_scenario_path(chosen)) return chosen;
  const std::string shipped = shipped_dir + "/" + chosen + ".yaml";
  if (!std::filesystem::is_regular_file(shipped))
    throw std::invalid_argument("CSP_SCENARIO=`" + chosen + "` is neither a scenario file nor a shipped scenario (" +
                                shipped + " does not exist)");
  return shipped;
}

}  // namespace csp::franka_address
