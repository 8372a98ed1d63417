#include "csp/can/object_values.hpp"

#include <stdexcept>
#include <utility>

#include "csp/can/frame.hpp"

namespace csp::can {

ObjectValues::ObjectValues(ObjectTable table, uint8_t node_id)
    : table_(std::move(table)), node_id_(node_id), values_(table_.entries.size()) {}

int ObjectValues::slot(uint16_t index, uint8_t subindex) const {
  const int s = table_.find(index, subindex);
  if (s < 0) throw std::logic_error("object table lacks an object the drive uses");
  return s;
}

std::vector<uint8_t> ObjectValues::bytes(int slot) const {
  const Entry& e = table_.entries[slot];
  if (e.type == DataType::kVisibleString) return {e.text.begin(), e.text.end()};
  std::vector<uint8_t> bytes(size_of(e.type));
  put_le(bytes.data(), size_of(e.type), static_cast<uint64_t>(values_[slot]));
  return bytes;
}

int64_t ObjectValues::decode(int slot, const uint8_t* bytes, int size) const {
  const uint64_t raw = get_le(bytes, size);
  if (!is_signed(table_.entries[slot].type) || size == 8) return static_cast<int64_t>(raw);
  const uint64_t sign = uint64_t{1} << (8 * size - 1);
  return static_cast<int64_t>((raw ^ sign) - sign);   // sign extension
}

void ObjectValues::reset(bool communication_only) {
  for (size_t i = 0; i < table_.entries.size(); ++i) {
    const Entry& e = table_.entries[i];
    if (communication_only && e.index >= 0x2000) continue;
    values_[i] = e.default_value + (e.plus_node_id ? node_id_ : 0);
  }
}

}  // namespace csp::can
