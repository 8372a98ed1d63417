// The parameter block of the FCI model library (libcsp_fci_model.so): the robot model its 31
// functions compute with is not compiled in. The library holds one exported object,
// `csp_fci_model_parameters`, whose bytes start with a unique marker; the server (csp fci) finds
// the marker in a copy of the library's bytes, writes the scenario's robot model after it and
// sends that copy to libfranka (model_library.hpp).
//
// Layout (native byte order: the server and the library are built together for one machine):
//   offset  0  char[32]     kParameterBlockMarker, NUL-padded
//   offset 32  uint64       value_count: 0 as built ("never written"), kParameterCount once written
//   offset 40  double[135]  the robot model, in this order:
//                             7 MDH rows, joint 1 first: a, d, alpha, theta_offset       [m, rad]
//                             link7_T_flange as its 4x4 matrix, column-major (16)
//                             7 links, link 1 first: mass, com (x, y, z), inertia about the
//                             CoM column-major (9), in MDH frame i                       [kg, m, kg m^2]
// Only what libfranka's model functions do not get per call: no end effector or load (the total
// load and F_T_EE come with each call), no gravity (g_NE gets g_earth), no armature or friction
// (not part of libfranka's M, c, g).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "csp/dynamics/model.hpp"

namespace csp::fci {

// 31 characters and the NUL; appears exactly once in the built library (checked by the server).
inline constexpr char kParameterBlockMarker[32] = "CSP-FCI-MODEL-PARAMETER-BLOCK-1";

inline constexpr std::size_t kParameterCount = kNumJoints * 4 + 16 + kNumJoints * 13;

struct ParameterBlock {
  char marker[32];
  std::uint64_t value_count;
  double values[kParameterCount];
};
static_assert(offsetof(ParameterBlock, value_count) == 32 && offsetof(ParameterBlock, values) == 40);
static_assert(sizeof(ParameterBlock) == 40 + 8 * kParameterCount);

// The block as built: the marker, then zeros.
constexpr ParameterBlock unwritten_parameter_block() {
  ParameterBlock block{};
  for (std::size_t k = 0; k < sizeof block.marker; ++k) block.marker[k] = kParameterBlockMarker[k];
  return block;
}

// The values of the block for a robot model (its joints, flange and links only).
std::array<double, kParameterCount> encode_parameters(const ModelParameters& robot_model);

// The robot model of the block's values: joints, flange and links; everything else as a
// default-constructed ModelParameters has it (no end effector, no load, no armature, no friction).
ModelParameters decode_parameters(const double* values);

}  // namespace csp::fci
