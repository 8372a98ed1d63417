// Files generated from the one object table: the EDS (CiA 306 INI format, what CANopen masters
// load) and a DBC (what candump viewers, SavvyCAN and DBC decoders read). The EDS is the contract;
// the DBC describes the default PDO mapping, NMT, SYNC, EMCY and heartbeats for viewing.
#pragma once

#include <string>

#include "csp/can/drive_bus.hpp"

namespace csp::can {

// The EDS of the drive of joint `joint` (1..7); COB-IDs relative to $NODEID.
std::string make_eds(const JointDrive& drive, const Identity& identity = {});

// The DBC of the whole bus with its default mapping and node ids.
std::string make_dbc(const BusSettings& settings);

// A DBC factor in plain decimals ("0.000001", never "1e-06": some DBC readers drop signals with
// exponents).
std::string plain_decimal(double value);

}  // namespace csp::can
