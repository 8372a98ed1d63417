#include "csp/can/sdo_server.hpp"

#include <algorithm>
#include <utility>

namespace csp::can {

SdoServer::SdoServer(uint8_t node_id, const ObjectValues& values, ObjectWriter& writer, const NmtSlave& nmt,
                     std::vector<Frame>& out)
    : node_id_(node_id), values_(values), writer_(writer), nmt_(nmt), out_(out) {}

void SdoServer::send(const std::array<uint8_t, 8>& bytes) {
  Frame f;
  f.id = kSdoTx + node_id_;
  f.dlc = 8;
  f.data = bytes;
  out_.push_back(f);
}

void SdoServer::abort_transfer(uint16_t index, uint8_t subindex, uint32_t code) {
  std::array<uint8_t, 8> b{0x80, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), subindex};
  put_le(&b[4], 4, code);
  send(b);
  transfer_ = {};
}

int SdoServer::find_entry(uint16_t index, uint8_t subindex, bool for_write) {
  const ObjectTable& table = values_.table();
  if (table.object(index) == nullptr) return abort_transfer(index, subindex, abort::kNoObject), -1;
  const int s = table.find(index, subindex);
  if (s < 0) return abort_transfer(index, subindex, abort::kNoSubindex), -1;
  const Access a = table.entries[s].access;
  if (for_write && !writable(a)) return abort_transfer(index, subindex, abort::kReadOnly), -1;
  if (!for_write && !readable(a)) return abort_transfer(index, subindex, abort::kWriteOnly), -1;
  return s;
}

bool SdoServer::continues_transfer(Transfer::Kind kind, uint8_t command) {
  if (transfer_.kind != kind) return abort_transfer(0, 0, abort::kUnknownCommand), false;
  const bool toggle = command & 0x10;
  if (toggle == transfer_.toggle) return true;
  const Entry& e = values_.entry(transfer_.slot);
  abort_transfer(e.index, e.subindex, abort::kToggleBit);
  return false;
}

void SdoServer::receive(const Frame& request) {
  if (nmt_.state() == NmtState::kStopped || request.dlc != 8) return;   // CiA 301: SDO needs all 8 bytes
  const uint8_t* d = request.data.data();
  const int command = d[0] >> 5;
  const uint16_t index = static_cast<uint16_t>(d[1] | (d[2] << 8));
  const uint8_t subindex = d[3];
  switch (command) {
    case 1: {   // initiate download: e = bit 1, s = bit 0, n = bits 2-3
      const int s = find_entry(index, subindex, true);
      if (s < 0) return;
      const bool expedited = d[0] & 0x02, size_indicated = d[0] & 0x01;
      if (expedited) {
        const int type_size = std::max(size_of(values_.entry(s).type), 1);
        const size_t size = size_indicated ? 4 - ((d[0] >> 2) & 0x3) : static_cast<size_t>(type_size);
        const uint32_t code = write(s, d + 4, size);
        if (code != 0) return abort_transfer(index, subindex, code);
        send({0x60, d[1], d[2], subindex, 0, 0, 0, 0});
        return;
      }
      transfer_ = {Transfer::Kind::kDownload, s, false, {}, 0};
      send({0x60, d[1], d[2], subindex, 0, 0, 0, 0});
      return;
    }
    case 0: {   // download segment: t = bit 4, n = bits 1-3, c = bit 0
      if (!continues_transfer(Transfer::Kind::kDownload, d[0])) return;
      const Entry& e = values_.entry(transfer_.slot);
      const bool toggle = transfer_.toggle;
      const int n = 7 - ((d[0] >> 1) & 0x7);
      if (transfer_.data.size() + n > 8) return abort_transfer(e.index, e.subindex, abort::kLengthTooHigh);
      transfer_.data.insert(transfer_.data.end(), d + 1, d + 1 + n);
      if (d[0] & 0x01) {   // last segment: the value is written (or refused) before the answer
        const uint32_t code = write(transfer_.slot, transfer_.data.data(), transfer_.data.size());
        if (code != 0) return abort_transfer(e.index, e.subindex, code);
        transfer_ = {};
      } else {
        transfer_.toggle = !transfer_.toggle;
      }
      send({static_cast<uint8_t>(0x20 | (toggle ? 0x10 : 0)), 0, 0, 0, 0, 0, 0, 0});
      return;
    }
    case 2: {   // initiate upload
      const int s = find_entry(index, subindex, false);
      if (s < 0) return;
      std::vector<uint8_t> bytes = values_.bytes(s);
      if (bytes.size() <= 4) {   // expedited: 0x4F / 0x4B / 0x47 / 0x43 for 1..4 bytes
        std::array<uint8_t, 8> b{static_cast<uint8_t>(0x43 | ((4 - bytes.size()) << 2)), d[1], d[2], subindex};
        std::copy(bytes.begin(), bytes.end(), b.begin() + 4);
        send(b);
        return;
      }
      std::array<uint8_t, 8> b{0x41, d[1], d[2], subindex};   // segmented, size indicated
      put_le(&b[4], 4, bytes.size());
      send(b);
      transfer_ = {Transfer::Kind::kUpload, s, false, std::move(bytes), 0};
      return;
    }
    case 3: {   // upload segment
      if (!continues_transfer(Transfer::Kind::kUpload, d[0])) return;
      const bool toggle = transfer_.toggle;
      const size_t n = std::min<size_t>(7, transfer_.data.size() - transfer_.offset);
      const bool last = transfer_.offset + n == transfer_.data.size();
      std::array<uint8_t, 8> b{static_cast<uint8_t>((toggle ? 0x10 : 0) | ((7 - n) << 1) | (last ? 1 : 0))};
      std::copy_n(transfer_.data.begin() + static_cast<long>(transfer_.offset), n, b.begin() + 1);
      send(b);
      transfer_.offset += n;
      transfer_.toggle = !transfer_.toggle;
      if (last) transfer_ = {};
      return;
    }
    case 4: transfer_ = {}; return;   // the client aborts: no answer
    default: abort_transfer(index, subindex, abort::kUnknownCommand); return;   // block transfers are not supported
  }
}

uint32_t SdoServer::write(int slot, const uint8_t* bytes, size_t size) {
  const size_t type_size = static_cast<size_t>(size_of(values_.entry(slot).type));
  if (size > type_size) return abort::kLengthTooHigh;
  if (size < type_size) return abort::kLengthTooLow;
  return writer_.write(slot, values_.decode(slot, bytes, static_cast<int>(size)));
}

}  // namespace csp::can
