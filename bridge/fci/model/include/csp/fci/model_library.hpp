// The model library csp fci sends libfranka (up to 0.13) for LoadModelLibrary: the bytes of
// libcsp_fci_model.so with the robot's model written into its parameter block
// (model_parameter_block.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "csp/dynamics/model.hpp"

namespace csp::fci {

// Where libcsp_fci_model.so is: next to an installed csp (<prefix>/<libdir>/csp/), else the
// build tree's, else the install location.
std::string model_library_path();

// The bytes of the library at `library_path` (by default model_library_path()) with `robot_model`'s
// joints, flange and links in its parameter block. Throws std::runtime_error naming the file when
// it cannot be read, has no parameter block or more than one, or the model has a non-finite value.
std::vector<std::uint8_t> model_library_for(const ModelParameters& robot_model);
std::vector<std::uint8_t> model_library_for(const ModelParameters& robot_model, const std::string& library_path);

}  // namespace csp::fci
