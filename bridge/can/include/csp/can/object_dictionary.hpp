// The one object-dictionary table of a CSP joint drive: CiA 301 communication objects, CiA 402
// drive objects and the manufacturer objects of Franka's semantics. The SDO server, the PDO
// engine, the EDS and the DBC are all driven by this table (docs/can.md has it as a table too).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace csp::can {

// CiA 301 data type codes (the numbers an EDS writes as DataType).
enum class DataType : uint16_t {
  kBoolean = 0x0001,
  kInteger8 = 0x0002,
  kInteger16 = 0x0003,
  kInteger32 = 0x0004,
  kUnsigned8 = 0x0005,
  kUnsigned16 = 0x0006,
  kUnsigned32 = 0x0007,
  kVisibleString = 0x0009,
};
// Size in bytes; 0 for a visible string (its length is the text's).
int size_of(DataType type);
bool is_signed(DataType type);

enum class Access { kReadOnly, kWriteOnly, kReadWrite, kConst };
const char* access_name(Access access);   // as an EDS writes it: ro, wo, rw, const
inline bool readable(Access a) { return a != Access::kWriteOnly; }
inline bool writable(Access a) { return a == Access::kWriteOnly || a == Access::kReadWrite; }

enum class ObjectCode : uint8_t { kVar = 0x7, kArray = 0x8, kRecord = 0x9 };

// One value of the dictionary (an object's sub-index).
struct Entry {
  uint16_t index = 0;
  uint8_t subindex = 0;
  std::string name;
  DataType type = DataType::kUnsigned8;
  Access access = Access::kReadOnly;
  bool pdo_mappable = false;
  int64_t low = 0, high = 0;     // allowed raw values (SDO aborts outside)
  int64_t default_value = 0;
  bool plus_node_id = false;     // the default is default_value + node id ("$NODEID+0x180" in the EDS)
  std::string text;              // the value of a visible string
  std::string unit;              // what one raw step means, e.g. "urad"
};

struct Object {
  uint16_t index = 0;
  std::string name;
  ObjectCode code = ObjectCode::kVar;
  int first = 0, count = 0;      // its entries in ObjectTable::entries
};

struct ObjectTable {
  std::vector<Object> objects;   // ascending index
  std::vector<Entry> entries;    // ascending (index, sub-index)

  // Position of (index, subindex) in `entries`, or -1.
  int find(uint16_t index, uint8_t subindex) const;
  const Object* object(uint16_t index) const;
};

// The identity (0x1018) every node reports. CSP has no CiA vendor id: 0 = not assigned.
struct Identity {
  uint32_t vendor_id = 0;
  uint32_t product_code = 0x00435350;   // "CSP"
  uint32_t revision = 0x00010000;
};

// What one joint drive's table depends on. Torques are per mille of the rated torque 0x6076, so
// the rated torque sets both range and resolution: INT16 reaches 32.767 x rated.
struct JointDrive {
  int joint = 1;                        // 1..7
  uint32_t rated_torque_mNm = 3000;     // 0x6076; one torque step = rated / 1000
  uint16_t max_torque_per_mille = 0;    // 0x6072: the joint's torque limit
  int32_t position_min_urad = 0, position_max_urad = 0;   // 0x607D
  uint32_t max_velocity_urad_s = 0;     // 0x6080
};

// The Panda/FR3 joint drive `joint` (1..7): limits from configs/robots/panda.yaml (Franka's
// "Limits for Panda"): tau_max 87 N m (joints 1-4) and 12 N m (5-7) with rated torques of
// 3000 and 500 mN m, i.e. 3 and 0.5 mN m per step and ranges of +-98.3 and +-16.4 N m.
JointDrive panda_joint_drive(int joint);

// The dictionary of one joint drive; identical for all nodes but the node-id-relative defaults.
ObjectTable object_table(const JointDrive& drive, const Identity& identity = {});

// Franka's errors (libfranka names, rt::Error order) as the drive reports them: 0x2002 sub i+1 is
// error i; each has an EMCY code (docs/can.md).
uint16_t emcy_code_of_error(int error);

// Objects the drive logic uses by name.
namespace od {
inline constexpr uint16_t kDeviceType = 0x1000, kErrorRegister = 0x1001, kCobIdSync = 0x1005,
                          kCommunicationCyclePeriod = 0x1006, kSyncWindowLength = 0x1007,
                          kDeviceName = 0x1008, kCobIdEmcy = 0x1014, kConsumerHeartbeatTime = 0x1016,
                          kProducerHeartbeatTime = 0x1017, kIdentity = 0x1018, kRpdoCommunication = 0x1400,
                          kRpdoMapping = 0x1600, kTpdoCommunication = 0x1800, kTpdoMapping = 0x1A00;
inline constexpr uint16_t kGravityCompensation = 0x2000, kTauExtHatFiltered = 0x2001, kCurrentErrors = 0x2002,
                          kAutomaticErrorRecovery = 0x2003;
inline constexpr uint16_t kControlword = 0x6040, kStatusword = 0x6041, kQuickStopOptionCode = 0x605A,
                          kModesOfOperation = 0x6060, kModesOfOperationDisplay = 0x6061,
                          kPositionDemandValue = 0x6062, kPositionActualValue = 0x6064, kVelocityActualValue = 0x606C, kTargetTorque = 0x6071,
                          kMaxTorque = 0x6072, kTorqueDemand = 0x6074, kMotorRatedTorque = 0x6076,
                          kTorqueActualValue = 0x6077, kTargetPosition = 0x607A, kSoftwarePositionLimit = 0x607D,
                          kMaxMotorSpeed = 0x6080, kVelocityOffset = 0x60B1, kTorqueOffset = 0x60B2,
                          kInterpolationTimePeriod = 0x60C2, kTargetVelocity = 0x60FF,
                          kSupportedDriveModes = 0x6502;
inline constexpr int kNumRpdos = 4, kNumTpdos = 2;
}  // namespace od

// CiA 402 modes of operation (0x6060) CSP supports (0x6502 bit mode-1).
inline constexpr int8_t kModeCsp = 8, kModeCsv = 9, kModeCst = 10;

}  // namespace csp::can
