#include "csp/can/object_dictionary.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "csp/can/frame.hpp"
#include "csp/rt/errors.hpp"

namespace csp::can {

int size_of(DataType type) {
  switch (type) {
    case DataType::kBoolean:
    case DataType::kInteger8:
    case DataType::kUnsigned8: return 1;
    case DataType::kInteger16:
    case DataType::kUnsigned16: return 2;
    case DataType::kInteger32:
    case DataType::kUnsigned32: return 4;
    case DataType::kVisibleString: return 0;
  }
  return 0;
}

bool is_signed(DataType type) {
  return type == DataType::kInteger8 || type == DataType::kInteger16 || type == DataType::kInteger32;
}

const char* access_name(Access access) {
  switch (access) {
    case Access::kReadOnly: return "ro";
    case Access::kWriteOnly: return "wo";
    case Access::kReadWrite: return "rw";
    case Access::kConst: return "const";
  }
  return "ro";
}

int ObjectTable::find(uint16_t index, uint8_t subindex) const {
  const auto it = std::lower_bound(entries.begin(), entries.end(), std::pair{index, subindex},
                                   [](const Entry& e, const std::pair<uint16_t, uint8_t>& key) {
                                     return e.index < key.first || (e.index == key.first && e.subindex < key.second);
                                   });
  if (it == entries.end() || it->index != index || it->subindex != subindex) return -1;
  return static_cast<int>(it - entries.begin());
}

const Object* ObjectTable::object(uint16_t index) const {
  const auto it = std::lower_bound(objects.begin(), objects.end(), index,
                                   [](const Object& o, uint16_t key) { return o.index < key; });
  return it != objects.end() && it->index == index ? &*it : nullptr;
}

JointDrive panda_joint_drive(int joint) {
  if (joint < 1 || joint > 7) throw std::invalid_argument("joint drive: joint must be 1..7, got " + std::to_string(joint));
  // configs/robots/panda.yaml, limits.joint franka_docs (Franka's "Limits for Panda").
  constexpr std::array<double, 7> q_min{-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973};
  constexpr std::array<double, 7> q_max{2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973};
  constexpr std::array<double, 7> dq_max{2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61};
  constexpr std::array<double, 7> tau_max{87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0};
  const int i = joint - 1;
  JointDrive drive;
  drive.joint = joint;
  drive.rated_torque_mNm = i < 4 ? 3000 : 500;
  drive.max_torque_per_mille = static_cast<uint16_t>(std::lround(tau_max[i] * 1e6 / drive.rated_torque_mNm));
  drive.position_min_urad = static_cast<int32_t>(std::lround(q_min[i] * 1e6));
  drive.position_max_urad = static_cast<int32_t>(std::lround(q_max[i] * 1e6));
  drive.max_velocity_urad_s = static_cast<uint32_t>(std::lround(dq_max[i] * 1e6));
  return drive;
}

uint16_t emcy_code_of_error(int error) {
  // CiA 301 0x8250 "RPDO timeout" is what libfranka's communication_constraints_violation is on
  // this bus; every other reflex gets a device-specific code 0xFF01.. (CiA 301: 0xFFxx).
  if (error == static_cast<int>(rt::Error::communication_constraints_violation)) return 0x8250;
  return static_cast<uint16_t>(0xFF01 + error);
}

namespace {

constexpr int64_t kI8Min = -128, kI8Max = 127, kI16Min = -32768, kI16Max = 32767;
constexpr int64_t kI32Min = std::numeric_limits<int32_t>::min(), kI32Max = std::numeric_limits<int32_t>::max();
constexpr int64_t kU8Max = 0xFF, kU16Max = 0xFFFF, kU32Max = 0xFFFFFFFF;

// Builds the table object by object, entries in order.
class TableBuilder {
 public:
  void var(uint16_t index, const std::string& name, DataType type, Access access, int64_t value, bool mappable = false,
           int64_t low = 0, int64_t high = -1, const std::string& unit = "") {
    begin(index, name, ObjectCode::kVar);
    entry(0, name, type, access, value, mappable, low, high, unit);
  }
  void begin(uint16_t index, const std::string& name, ObjectCode code) {
    table.objects.push_back({index, name, code, static_cast<int>(table.entries.size()), 0});
  }
  Entry& entry(uint8_t sub, const std::string& name, DataType type, Access access, int64_t value, bool mappable = false,
               int64_t low = 0, int64_t high = -1, const std::string& unit = "") {
    Entry e;
    e.index = table.objects.back().index;
    e.subindex = sub;
    e.name = name;
    e.type = type;
    e.access = access;
    e.pdo_mappable = mappable;
    e.default_value = value;
    e.unit = unit;
    if (high < low) std::tie(e.low, e.high) = full_range(type);   // no narrower range given
    else std::tie(e.low, e.high) = std::pair{low, high};
    table.entries.push_back(e);
    ++table.objects.back().count;
    return table.entries.back();
  }
  // An array/record's sub-index 0: the highest sub-index.
  void count(uint8_t highest) { entry(0, "Highest sub-index supported", DataType::kUnsigned8, Access::kConst, highest); }

  static std::pair<int64_t, int64_t> full_range(DataType type) {
    switch (type) {
      case DataType::kBoolean: return {0, 1};
      case DataType::kInteger8: return {kI8Min, kI8Max};
      case DataType::kInteger16: return {kI16Min, kI16Max};
      case DataType::kInteger32: return {kI32Min, kI32Max};
      case DataType::kUnsigned8: return {0, kU8Max};
      case DataType::kUnsigned16: return {0, kU16Max};
      case DataType::kUnsigned32: return {0, kU32Max};
      case DataType::kVisibleString: return {0, 0};
    }
    return {0, 0};
  }

  ObjectTable table;
};

constexpr int64_t mapping(uint16_t index, uint8_t sub, int bits) {
  return (int64_t{index} << 16) | (int64_t{sub} << 8) | bits;
}

}  // namespace

ObjectTable object_table(const JointDrive& drive, const Identity& identity) {
  using DT = DataType;
  using A = Access;
  TableBuilder b;
  // --- CiA 301 communication objects ---
  // 0x1000: profile 402 (0x0192) in the low word, 0x0002 = servo drive in the high word.
  b.var(od::kDeviceType, "Device type", DT::kUnsigned32, A::kConst, 0x00020192);
  b.var(od::kErrorRegister, "Error register", DT::kUnsigned8, A::kReadOnly, 0, true);
  b.var(od::kCobIdSync, "COB-ID SYNC", DT::kUnsigned32, A::kReadWrite, 0x80, false, 0x80, 0x80);
  // The emulated robot's cycle is 1 ms: one SYNC = one FCI cycle.
  b.var(od::kCommunicationCyclePeriod, "Communication cycle period", DT::kUnsigned32, A::kReadWrite, 1000, false, 1000,
        1000, "us");
  b.var(od::kSyncWindowLength, "Synchronous window length", DT::kUnsigned32, A::kReadWrite, 0, false, 0, 0, "us");
  b.var(od::kDeviceName, "Manufacturer device name", DT::kVisibleString, A::kConst, 0);
  b.table.entries.back().text = "CSP emulated Franka joint drive";
  b.var(od::kCobIdEmcy, "COB-ID EMCY", DT::kUnsigned32, A::kReadWrite, 0x80);
  b.table.entries.back().plus_node_id = true;
  b.begin(od::kConsumerHeartbeatTime, "Consumer heartbeat time", ObjectCode::kArray);
  b.count(1);
  b.entry(1, "Consumer heartbeat time 1", DT::kUnsigned32, A::kReadWrite, 0, false, 0, 0x007FFFFF);
  b.var(od::kProducerHeartbeatTime, "Producer heartbeat time", DT::kUnsigned16, A::kReadWrite, 100, false, 0, kU16Max, "ms");
  b.begin(od::kIdentity, "Identity object", ObjectCode::kRecord);
  b.count(4);
  b.entry(1, "Vendor-ID", DT::kUnsigned32, A::kReadOnly, identity.vendor_id);
  b.entry(2, "Product code", DT::kUnsigned32, A::kReadOnly, identity.product_code);
  b.entry(3, "Revision number", DT::kUnsigned32, A::kReadOnly, identity.revision);
  b.entry(4, "Serial number", DT::kUnsigned32, A::kReadOnly, drive.joint);

  // PDOs (docs/can.md message table). RPDO 1-3 are synchronous (latched at the next SYNC),
  // RPDO4 (the mode) takes effect on arrival; TPDOs go out at every SYNC.
  struct Pdo {
    uint32_t cob_base;
    int transmission_type;
    std::vector<int64_t> map;
  };
  const std::array<Pdo, od::kNumRpdos> rpdos{{
      {kRpdo1, 1, {mapping(od::kControlword, 0, 16), mapping(od::kTargetTorque, 0, 16)}},
      {kRpdo2, 1, {mapping(od::kTargetPosition, 0, 32), mapping(od::kTorqueOffset, 0, 16)}},
      {kRpdo3, 1, {mapping(od::kTargetVelocity, 0, 32), mapping(od::kTorqueOffset, 0, 16)}},
      {kRpdo4, 255, {mapping(od::kModesOfOperation, 0, 8)}},
  }};
  const std::array<Pdo, od::kNumTpdos> tpdos{{
      {kTpdo1, 1, {mapping(od::kStatusword, 0, 16), mapping(od::kPositionActualValue, 0, 32),
                  mapping(od::kTorqueActualValue, 0, 16)}},
      {kTpdo2, 1, {mapping(od::kVelocityActualValue, 0, 32), mapping(od::kTauExtHatFiltered, 0, 16),
                  mapping(od::kModesOfOperationDisplay, 0, 8)}},
  }};
  auto communication = [&](uint16_t index, const Pdo& pdo, const char* kind, int number) {
    const std::string n = std::to_string(number);
    b.begin(index, std::string(kind) + " communication parameter " + n, ObjectCode::kRecord);
    b.count(2);
    b.entry(1, std::string("COB-ID used by ") + kind + " " + n, DT::kUnsigned32, A::kReadWrite, pdo.cob_base)
        .plus_node_id = true;
    b.entry(2, "Transmission type", DT::kUnsigned8, A::kReadWrite, pdo.transmission_type);
  };
  auto mapping_parameter = [&](uint16_t index, const Pdo& pdo, const char* kind, int number) {
    b.begin(index, std::string(kind) + " mapping parameter " + std::to_string(number), ObjectCode::kRecord);
    b.entry(0, "Number of mapped objects", DT::kUnsigned8, A::kReadWrite, static_cast<int64_t>(pdo.map.size()), false, 0, 8);
    for (int i = 0; i < 8; ++i)
      b.entry(static_cast<uint8_t>(i + 1), "Mapped object " + std::to_string(i + 1), DT::kUnsigned32, A::kReadWrite,
              i < static_cast<int>(pdo.map.size()) ? pdo.map[i] : 0);
  };
  for (int i = 0; i < od::kNumRpdos; ++i) communication(static_cast<uint16_t>(od::kRpdoCommunication + i), rpdos[i], "RPDO", i + 1);
  for (int i = 0; i < od::kNumRpdos; ++i) mapping_parameter(static_cast<uint16_t>(od::kRpdoMapping + i), rpdos[i], "RPDO", i + 1);
  for (int i = 0; i < od::kNumTpdos; ++i) communication(static_cast<uint16_t>(od::kTpdoCommunication + i), tpdos[i], "TPDO", i + 1);
  for (int i = 0; i < od::kNumTpdos; ++i) mapping_parameter(static_cast<uint16_t>(od::kTpdoMapping + i), tpdos[i], "TPDO", i + 1);

  // --- Manufacturer objects: Franka's semantics ---
  b.var(od::kGravityCompensation, "gravity_compensation", DT::kUnsigned8, A::kReadWrite, 1, false, 0, 1);
  b.var(od::kTauExtHatFiltered, "tau_ext_hat_filtered", DT::kInteger16, A::kReadOnly, 0, true, kI16Min, kI16Max,
        "per mille of rated torque");
  b.begin(od::kCurrentErrors, "current_errors", ObjectCode::kArray);
  b.count(rt::kNumErrors);
  for (int i = 0; i < rt::kNumErrors; ++i)
    b.entry(static_cast<uint8_t>(i + 1), rt::error_name(static_cast<rt::Error>(i)), DT::kUnsigned8, A::kReadOnly, 0, false,
            0, 1);
  b.var(od::kAutomaticErrorRecovery, "automatic_error_recovery", DT::kUnsigned8, A::kWriteOnly, 0, false, 1, 1);

  // --- CiA 402 drive objects ---
  b.var(od::kControlword, "Controlword", DT::kUnsigned16, A::kReadWrite, 0, true);
  b.var(od::kStatusword, "Statusword", DT::kUnsigned16, A::kReadOnly, 0, true);
  b.var(od::kQuickStopOptionCode, "Quick stop option code", DT::kInteger16, A::kReadWrite, 2, false, 0, 8);
  b.var(od::kModesOfOperation, "Modes of operation", DT::kInteger8, A::kReadWrite, kModeCst, true, kModeCsp, kModeCst);
  b.var(od::kModesOfOperationDisplay, "Modes of operation display", DT::kInteger8, A::kReadOnly, kModeCst, true);
  // q_d: where a CSP motion must start (libfranka's motion generators start from q_d, not q).
  b.var(od::kPositionDemandValue, "Position demand value", DT::kInteger32, A::kReadOnly, 0, true, kI32Min, kI32Max, "urad");
  b.var(od::kPositionActualValue, "Position actual value", DT::kInteger32, A::kReadOnly, 0, true, kI32Min, kI32Max, "urad");
  b.var(od::kVelocityActualValue, "Velocity actual value", DT::kInteger32, A::kReadOnly, 0, true, kI32Min, kI32Max,
        "urad/s");
  b.var(od::kTargetTorque, "Target torque", DT::kInteger16, A::kReadWrite, 0, true, kI16Min, kI16Max, "per mille of rated torque");
  b.var(od::kMaxTorque, "Max torque", DT::kUnsigned16, A::kReadWrite, drive.max_torque_per_mille, false, 0,
        drive.max_torque_per_mille, "per mille of rated torque");
  b.var(od::kTorqueDemand, "Torque demand", DT::kInteger16, A::kReadOnly, 0, true, kI16Min, kI16Max, "per mille of rated torque");
  b.var(od::kMotorRatedTorque, "Motor rated torque", DT::kUnsigned32, A::kConst, drive.rated_torque_mNm, false, 0, kU32Max,
        "mN m");
  b.var(od::kTorqueActualValue, "Torque actual value", DT::kInteger16, A::kReadOnly, 0, true, kI16Min, kI16Max,
        "per mille of rated torque");
  b.var(od::kTargetPosition, "Target position", DT::kInteger32, A::kReadWrite, 0, true, kI32Min, kI32Max, "urad");
  b.begin(od::kSoftwarePositionLimit, "Software position limit", ObjectCode::kArray);
  b.count(2);
  b.entry(1, "Min position limit", DT::kInteger32, A::kReadOnly, drive.position_min_urad, false, kI32Min, kI32Max, "urad");
  b.entry(2, "Max position limit", DT::kInteger32, A::kReadOnly, drive.position_max_urad, false, kI32Min, kI32Max, "urad");
  b.var(od::kMaxMotorSpeed, "Max motor speed", DT::kUnsigned32, A::kReadOnly, drive.max_velocity_urad_s, false, 0, kU32Max,
        "urad/s");
  b.var(od::kVelocityOffset, "Velocity offset", DT::kInteger32, A::kReadWrite, 0, true, kI32Min, kI32Max, "urad/s");
  b.var(od::kTorqueOffset, "Torque offset", DT::kInteger16, A::kReadWrite, 0, true, kI16Min, kI16Max, "per mille of rated torque");
  // 0x60C2: value x 10^index s; 1 x 10^-3 s = the 1 ms cycle (ros2_canopen writes it).
  b.begin(od::kInterpolationTimePeriod, "Interpolation time period", ObjectCode::kRecord);
  b.count(2);
  b.entry(1, "Interpolation time period value", DT::kUnsigned8, A::kReadWrite, 1, false, 1, 1);
  b.entry(2, "Interpolation time index", DT::kInteger8, A::kReadWrite, -3, false, -3, -3);
  b.var(od::kTargetVelocity, "Target velocity", DT::kInteger32, A::kReadWrite, 0, true, kI32Min, kI32Max, "urad/s");
  // Bit mode-1: 7 = CSP, 8 = CSV, 9 = CST.
  b.var(od::kSupportedDriveModes, "Supported drive modes", DT::kUnsigned32, A::kConst, 0x380);
  return std::move(b.table);
}

}  // namespace csp::can
