// One node's object dictionary as it runs: the table (what each entry is) and each entry's
// current raw value, which SDOs read and write and PDOs carry. The services of a node share it.
#pragma once

#include <cstdint>
#include <vector>

#include "csp/can/object_dictionary.hpp"

namespace csp::can {

class ObjectValues {
 public:
  ObjectValues(ObjectTable table, uint8_t node_id);

  const ObjectTable& table() const { return table_; }
  const Entry& entry(int slot) const { return table_.entries[slot]; }
  // Position of an entry the node's logic uses; std::logic_error if the table lacks it.
  int slot(uint16_t index, uint8_t subindex) const;

  int64_t& operator[](int slot) { return values_[slot]; }
  int64_t operator[](int slot) const { return values_[slot]; }
  // The value as an SDO upload carries it: little-endian, a visible string's text.
  std::vector<uint8_t> bytes(int slot) const;
  // The value of `size` little-endian bytes from the bus, sign-extended for a signed type.
  int64_t decode(int slot, const uint8_t* bytes, int size) const;

  // The defaults again: of every entry (NMT reset node), or of the communication profile area
  // 0x1000-0x1FFF only (NMT reset communication, CiA 301).
  void reset(bool communication_only);

 private:
  ObjectTable table_;
  uint8_t node_id_;
  std::vector<int64_t> values_;
};

// Where SDO downloads and RPDOs put a value: the node checks it against the entry's range and
// the rules of the service that owns the entry, stores it, and applies what it means (the 402
// state machine on a controlword, the PDOs rebuilt on a new mapping), as CANopenNode's object
// dictionary extensions do.
class ObjectWriter {
 public:
  // 0 once stored, or the SDO abort code that refuses the value.
  virtual uint32_t write(int slot, int64_t value) = 0;

 protected:
  ~ObjectWriter() = default;
};

}  // namespace csp::can
