// CSP's FCI version 7 wire format against libfranka 0.13.3's research-interface headers (fci_protocol_checks.hpp).
#include <array>
#include <chrono>
#include <cstdint>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <type_traits>

// libfranka 0.13.3's headers in a namespace of their own: the other version's test declares the same names.
namespace vendor_v7 {
#include <include/research_interface/robot/error.h>
#include <include/research_interface/robot/rbk_types.h>
#include <include/research_interface/robot/service_types.h>
#include <include/research_interface/gripper/types.h>
#include <include/research_interface/vacuum_gripper/types.h>
}  // namespace vendor_v7

#define CSP_FCI_VERSION 7
#define CSP_FCI_VENDOR vendor_v7
#define CSP_FCI_SUITE FciProtocolV7
#include "fci_protocol_checks.hpp"
