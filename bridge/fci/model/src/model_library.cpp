#include "csp/fci/model_library.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "csp/fci/model_parameter_block.hpp"

namespace csp::fci {

std::string model_library_path() {
  std::error_code error;
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&model_library_path), &info) != 0 && info.dli_fname != nullptr) {
    const std::filesystem::path installed = std::filesystem::path(info.dli_fname).parent_path().parent_path() /
                                            CSP_FCI_MODEL_LIBRARY_INSTALLED_RELATIVE;
    if (std::filesystem::is_regular_file(installed, error)) return installed.string();
  }
  if (std::filesystem::is_regular_file(CSP_FCI_MODEL_LIBRARY_BUILT, error)) return CSP_FCI_MODEL_LIBRARY_BUILT;
  return CSP_FCI_MODEL_LIBRARY_INSTALLED;
}

std::vector<std::uint8_t> model_library_for(const ModelParameters& robot_model) {
  return model_library_for(robot_model, model_library_path());
}

std::vector<std::uint8_t> model_library_for(const ModelParameters& robot_model, const std::string& library_path) {
  auto fail = [&library_path](const std::string& what) {
    return std::runtime_error("FCI model library " + library_path + ": " + what);
  };
  std::ifstream in(library_path, std::ios::binary);
  if (!in) throw fail("cannot open it");
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw fail("cannot read it");

  const auto* marker = reinterpret_cast<const std::uint8_t*>(kParameterBlockMarker);
  const auto find_marker = [&](std::vector<std::uint8_t>::iterator from) {
    return std::search(from, bytes.end(), marker, marker + sizeof kParameterBlockMarker);
  };
  const auto block = find_marker(bytes.begin());
  if (block == bytes.end()) throw fail("no parameter block (its marker is not in the file: not libcsp_fci_model.so?)");
  if (find_marker(block + 1) != bytes.end()) throw fail("more than one parameter block marker");
  if (bytes.end() - block < static_cast<std::ptrdiff_t>(sizeof(ParameterBlock)))
    throw fail("the parameter block is cut off by the end of the file");

  const std::array<double, kParameterCount> values = encode_parameters(robot_model);
  if (!std::all_of(values.begin(), values.end(), [](double value) { return std::isfinite(value); }))
    throw fail("the robot model to write has a non-finite value");
  const std::uint64_t value_count = kParameterCount;
  std::memcpy(&*block + offsetof(ParameterBlock, value_count), &value_count, sizeof value_count);
  std::memcpy(&*block + offsetof(ParameterBlock, values), values.data(), sizeof values);
  return bytes;
}

}  // namespace csp::fci
