#!/usr/bin/env python3
"""Joint impedance control of the arm's seven CiA 402 drives over CAN, on python-can only
(docs/can.md): what csp_can_joint_impedance does, in Python.

    tau = K (q_d - q) - D dq,   q_d = q_0 + a (1 - cos(2 pi t / T)) on joints 1 and 4

in cyclic synchronous torque mode (CST); the robot adds gravity compensation itself. Each cycle:
RPDO1 (controlword, target torque) to every drive, SYNC, then the drives' TPDO1 (statusword,
position, torque) and TPDO2 (velocity, tau_ext, mode). The default mapping of `csp can eds`.
Works unchanged on vcan0 (csp can serve) and on a physical interface (can0):

    build/apps/csp can serve --iface vcan0 &
    python3 bridge/examples/can_joint_impedance.py --iface vcan0 --cycles 5000

Without kernel CAN (no vcan here), on a kernel booted in qemu, one command:

    bridge/can/tools/csp-can-sandbox --csp build/apps/csp -- /usr/bin/python3 bridge/examples/can_joint_impedance.py

Needs python-can (Debian: python3-can). The sync clock waits for the SYNC, so Python's speed
does not matter; with `--clock realtime` a cycle counts only if its RPDOs come within 1 ms.
"""
import argparse
import math
import struct
import sys

import can

NODES = range(1, 8)
# Gains below libfranka's joint_impedance_control: the torque answers the state of the previous
# SYNC (two cycles from measurement to torque instead of the FCI's one).
K = [300, 300, 300, 300, 120, 60, 20]    # [N m/rad]
D = [25, 25, 25, 10, 8, 5, 2]            # [N m s/rad]


class Drives:
    def __init__(self, iface, timeout):
        self.bus = can.interface.Bus(channel=iface, interface="socketcan")
        self.timeout = timeout
        self.torque_step = {}

    def send(self, cob_id, data=b""):
        self.bus.send(can.Message(arbitration_id=cob_id, data=data, is_extended_id=False))

    def receive(self, cob_ids):
        """The frames with these COB-IDs (one each); EMCY ends the program."""
        got = {}
        while len(got) < len(cob_ids):
            msg = self.bus.recv(self.timeout)
            if msg is None:
                sys.exit("no answer from the drives (COB-IDs %s)" % sorted(set(cob_ids) - set(got)))
            if 0x81 <= msg.arbitration_id <= 0x87:
                code, register = struct.unpack_from("<HB", msg.data)
                sys.exit("EMCY 0x%04X from node %d (error register 0x%02X)" % (code, msg.arbitration_id - 0x80, register))
            if msg.arbitration_id in cob_ids:
                got[msg.arbitration_id] = bytes(msg.data)
        return got

    def sdo(self, node, command, index, sub, value=0):
        """Expedited SDO (0x40 read; 0x2F/0x2B/0x23 write 1/2/4 bytes): the value read."""
        self.send(0x600 + node, struct.pack("<BHBI", command, index, sub, value))
        answer = self.receive([0x580 + node])[0x580 + node]
        if answer[0] == 0x80:
            sys.exit("node %d: SDO 0x%04X:%d aborted 0x%08X" % (node, index, sub, struct.unpack_from("<I", answer, 4)[0]))
        return struct.unpack_from("<I", answer, 4)[0]

    def start(self):
        for n in NODES:
            self.torque_step[n] = self.sdo(n, 0x40, 0x6076, 0) * 1e-6   # rated torque [mN m]: N m per per mille
            self.sdo(n, 0x2F, 0x6060, 0, 10)                            # modes of operation: CST
        self.send(0x000, bytes([0x01, 0x00]))                           # NMT start, all nodes

    def cycle(self, controlword, torques):
        """One cycle; per joint (statusword, q [rad], dq [rad/s])."""
        for n in NODES:
            raw = max(-32768, min(32767, round(torques[n - 1] / self.torque_step[n])))
            self.send(0x200 + n, struct.pack("<Hh", controlword, raw))
        self.send(0x080)
        frames = self.receive([0x180 + n for n in NODES] + [0x280 + n for n in NODES])
        return [(struct.unpack_from("<H", frames[0x180 + n])[0], struct.unpack_from("<i", frames[0x180 + n], 2)[0] * 1e-6,
                 struct.unpack_from("<i", frames[0x280 + n])[0] * 1e-6) for n in NODES]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iface", default="vcan0")
    parser.add_argument("--cycles", type=int, default=5000)
    parser.add_argument("--amplitude", type=float, default=0.1, help="motion of joints 1 and 4 [rad]")
    parser.add_argument("--period", type=float, default=4.0, help="period of the motion [s]")
    # 10 s: only how long a dead server takes to show; an emulated guest on a busy machine
    # stalls for far longer than a real bus ever makes a master wait (docs/can.md).
    parser.add_argument("--timeout", type=float, default=10.0, help="wait for answers [s]")
    args = parser.parse_args()

    drives = Drives(args.iface, args.timeout)
    drives.start()
    zero = [0.0] * 7
    state = drives.cycle(0x00, zero)
    # 402 walk: shutdown, switch on, enable operation (statusword under mask 0x6F: 0x21, 0x23, 0x27).
    for controlword, wanted in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
        for _ in range(10):
            state = drives.cycle(controlword, zero)
            if all(s & 0x6F == wanted for s, _, _ in state):
                break
        else:
            sys.exit("the drives do not follow controlword 0x%02X" % controlword)
    q0 = [q for _, q, _ in state]
    tau, max_error = zero, 0.0
    for k in range(args.cycles):
        state = drives.cycle(0x0F, tau)
        t = k * 1e-3
        tau = []
        for j, (_, q, dq) in enumerate(state):
            offset = args.amplitude * (1 - math.cos(2 * math.pi * t / args.period)) if j in (0, 3) else 0.0
            error = q0[j] + offset - q
            max_error = max(max_error, abs(error))
            tau.append(K[j] * error - D[j] * dq)
    drives.cycle(0x07, tau)   # disable operation: the motion finishes
    print("can_joint_impedance.py: %d cycles on %s, largest tracking error %.4f rad" % (args.cycles, args.iface, max_error))


if __name__ == "__main__":
    main()
