#!/usr/bin/python3
"""An independent CANopen master for the vcan test, on python-can only, written from the CiA 301
(NMT, SDO, SYNC, PDO, EMCY, heartbeat) and CiA 402 (controlword, statusword masks) text, not
from CSP's encoder. Runs inside the sandbox's guest (bridge/can/tools/csp-can-sandbox) against
`csp can serve`, which it starts itself once its own socket listens.

  master.py session  CSP REFERENCE WORK   boot, identity, 402 walk, 1000 CST cycles compared with
                                          the in-process emulator, RPDO silence -> EMCY + fault +
                                          recovery; the session log re-simulated by csp replay
  master.py badinput CSP WORK             wrong DLC, unknown COB-IDs, SDO errors, out-of-range
                                          values, 1e5 frames; the cycle goes on, the log is complete;
                                          a flood into a stopped server: dropped and late frames counted
  master.py fuzz CSP WORK STEPS [SEED]    random stateful sequences (NMT, SDO, COB-IDs, PDO remapping,
                                          402 transitions, modes, cycles) with invariants after each step
"""
import math
import os
import random
import re
import signal
import struct
import subprocess
import sys
import time

import can

NODES = range(1, 8)
TORQUE_STEP = [3e-3] * 4 + [0.5e-3] * 3      # 0x6076 = 3000 / 500 mN m, per mille [N m]
failures = []


def check(condition, what, quiet=False):
    """Prints the check (a passed `quiet` one is not printed: the fuzz checks thousands)."""
    if not (quiet and condition):
        print(("ok    " if condition else "FAIL  ") + what, flush=True)
    if not condition:
        failures.append(what)


class SdoAbort(Exception):
    def __init__(self, code):
        super().__init__("SDO abort 0x%08X" % code)
        self.code = code


class Master:
    def __init__(self, channel="vcan0"):
        self.bus = can.interface.Bus(channel=channel, interface="socketcan")
        self.emcy = []          # (node, code, register, byte 3) of every EMCY seen
        self.heartbeats = {}    # node -> last state byte

    def send(self, cob_id, data=b""):
        self.bus.send(can.Message(arbitration_id=cob_id, data=bytes(data), is_extended_id=False))

    def recv(self, timeout):
        msg = self.bus.recv(timeout)
        if msg is None or msg.is_extended_id or msg.is_remote_frame or msg.is_error_frame:
            return msg
        cob, data = msg.arbitration_id, bytes(msg.data)
        if 0x081 <= cob <= 0x0FF and len(data) == 8:     # EMCY: code U16, error register U8, ...
            self.emcy.append((cob - 0x80, data[0] | data[1] << 8, data[2], data[3]))
        if 0x701 <= cob <= 0x77F and len(data) == 1:     # heartbeat / boot-up
            self.heartbeats[cob - 0x700] = data[0]
        return msg

    def wait_for(self, wanted, timeout=5.0):
        """Frames until `wanted(msg)` is true; the matching message, or None after `timeout`."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = self.recv(max(0.0, deadline - time.monotonic()))
            if msg is not None and wanted(msg):
                return msg
        return None

    # --- SDO client (CiA 301 7.2.4.3): expedited and segmented upload, expedited download.
    def _sdo_request(self, node, request):
        self.send(0x600 + node, request)
        msg = self.wait_for(lambda m: m.arbitration_id == 0x580 + node)
        if msg is None:
            raise TimeoutError("no SDO answer from node %d" % node)
        data = bytes(msg.data)
        if data[0] == 0x80:
            raise SdoAbort(struct.unpack_from("<I", data, 4)[0])
        return data

    def upload(self, node, index, sub):
        data = self._sdo_request(node, struct.pack("<BHB4x", 0x40, index, sub))
        scs = data[0] >> 5
        assert scs == 2, "upload initiate answer 0x%02X" % data[0]
        if data[0] & 0x02:                                   # expedited
            size = 4 - ((data[0] >> 2) & 3) if data[0] & 0x01 else 4
            return data[4:4 + size]
        size = struct.unpack_from("<I", data, 4)[0]          # segmented: size indicated
        value, toggle = b"", 0
        while True:
            seg = self._sdo_request(node, bytes([0x60 | toggle << 4]) + bytes(7))
            assert seg[0] >> 5 == 0 and (seg[0] >> 4) & 1 == toggle, "segment 0x%02X" % seg[0]
            value += seg[1:8 - ((seg[0] >> 1) & 7)]
            if seg[0] & 1:
                assert len(value) == size
                return value
            toggle ^= 1

    def download(self, node, index, sub, value: bytes):
        n = len(value)
        command = 0x23 | (4 - n) << 2                        # expedited, size indicated
        answer = self._sdo_request(node, struct.pack("<BHB", command, index, sub) + value + bytes(4 - n))
        assert answer[0] == 0x60, "download answer 0x%02X" % answer[0]

    # --- the cycle: RPDOs, then SYNC, then the 14 TPDOs of that SYNC.
    def cycle(self, rpdos, timeout=5.0):
        for cob, data in rpdos:
            self.send(cob, data)
        self.send(0x080)
        got = {}
        deadline = time.monotonic() + timeout
        while len(got) < 14 and time.monotonic() < deadline:
            msg = self.recv(max(0.0, deadline - time.monotonic()))
            if msg is not None and (0x181 <= msg.arbitration_id <= 0x187 or 0x281 <= msg.arbitration_id <= 0x287):
                got[msg.arbitration_id] = bytes(msg.data)
        if len(got) < 14:
            raise TimeoutError("SYNC answered by %d of 14 TPDOs" % len(got))
        return got


def statuswords(tpdos):
    return [struct.unpack_from("<H", tpdos[0x180 + n])[0] for n in NODES]


def positions(tpdos):
    return [struct.unpack_from("<i", tpdos[0x180 + n], 2)[0] for n in NODES]


def velocities(tpdos):
    return [struct.unpack_from("<i", tpdos[0x280 + n])[0] for n in NODES]


def rpdo1(controlword, torques=(0,) * 7):
    return [(0x200 + n, struct.pack("<Hh", controlword, torques[n - 1])) for n in NODES]


# The master's frames in the order it sends them, as on a real bus: vcan queues each frame on the
# sending CPU's backlog, so a master moved between the guest's CPUs from one send to the next could
# have its SYNC delivered before its last RPDO (seen once on CI: a torn cycle, and the lockstep
# trajectory off by one command). So the master runs on one CPU; the server it starts on all of them.
ALL_CPUS = os.sched_getaffinity(0)


def start_serve(csp, work, name, *extra):
    out = open(os.path.join(work, name + ".out"), "w")
    return subprocess.Popen([csp, "can", "serve", "--iface", "vcan0", "--duration", "1000", *extra], stdout=out,
                            stderr=subprocess.STDOUT, preexec_fn=lambda: os.sched_setaffinity(0, ALL_CPUS))


def stop_serve(serve, work, name):
    serve.send_signal(signal.SIGINT)
    check(serve.wait(timeout=60) == 0, "%s: csp can serve ends cleanly on SIGINT" % name)
    with open(os.path.join(work, name + ".out")) as f:
        text = f.read()
    print(text, flush=True)
    return text


def boot(master, csp, work, name, *extra):
    serve = start_serve(csp, work, name, *extra)
    booted = set()
    while len(booted) < 7:
        msg = master.wait_for(lambda m: 0x701 <= m.arbitration_id <= 0x707 and bytes(m.data) == b"\x00", timeout=60)
        if msg is None:
            break
        booted.add(msg.arbitration_id - 0x700)
    check(booted == set(NODES), "boot-up 701#00 .. 707#00 from the seven nodes")
    return serve


def profile(k):
    """Target torques of cycle k, per mille: sines well inside libfranka's torque-rate limit."""
    amplitude = [1.0] * 4 + [0.1] * 3
    return [round(amplitude[j] * math.sin(2 * math.pi * (1.0 + 0.3 * j) * k * 1e-3) / TORQUE_STEP[j]) for j in range(7)]


def session(csp, reference, work):
    master = Master()
    log = os.path.join(work, "session.lcmlog")
    csv, replayed_csv = os.path.join(work, "session.csv"), os.path.join(work, "session_replayed.csv")
    serve = boot(master, csp, work, "session", "--log", log, "--csv", csv)

    master.send(0x000, [0x01, 0x00])                          # NMT start remote node, all nodes
    master.wait_for(lambda m: False, timeout=0.5)             # heartbeats (100 ms) show the new state
    check(all(master.heartbeats.get(n) == 0x05 for n in NODES), "NMT start: heartbeats 70n#05 (operational)")

    check(all(master.upload(n, 0x1000, 0) == struct.pack("<I", 0x00020192) for n in NODES), "0x1000 device type 0x00020192 (CiA 402 servo drive)")
    check(all(master.upload(n, 0x6502, 0) == struct.pack("<I", 0x380) for n in NODES), "0x6502 supported drive modes 0x380 (CSP, CSV, CST)")
    identity = [struct.unpack("<I", master.upload(1, 0x1018, s))[0] for s in (1, 2, 3, 4)]
    check(identity == [0, 0x00435350, 0x00010000, 1], "0x1018 identity of node 1: %s" % [hex(v) for v in identity])
    name = master.upload(3, 0x1008, 0)
    check(name == b"CSP emulated Franka joint drive", "0x1008 by segmented upload: %r" % name)
    try:
        master.upload(1, 0x1234, 0)
        check(False, "SDO to a missing object aborts")
    except SdoAbort as e:
        check(e.code == 0x06020000, "SDO to a missing object: abort 0x06020000 (got 0x%08X)" % e.code)

    # CiA 402 walk by RPDO1: an RPDO latched at SYNC k shows in the TPDO of SYNC k+1.
    syncs = 0
    expected = {0x06: 0x21, 0x07: 0x23, 0x0F: 0x27}          # statusword under mask 0x6F
    start = None
    tpdos = None
    for controlword, state in expected.items():
        master.cycle(rpdo1(controlword))
        if controlword == 0x0F:
            start = syncs                                     # this SYNC's cycle starts the motion
        syncs += 1
        tpdos = master.cycle(rpdo1(controlword))
        syncs += 1
        check(all(s & 0x6F == state for s in statuswords(tpdos)), "controlword 0x%02X -> statusword 0x%02X" % (controlword, state))
    # The cycles since the start, as the reference must run them: zero torque from the walk's RPDOs.
    commands = [[0] * 7, [0] * 7]

    # 1000 CST cycles with a torque profile; TPDOs of SYNC k+1 = the state after cycle k.
    trajectory = []
    for k in range(1000):
        torques = profile(k)
        commands.append(torques)
        tpdos = master.cycle(rpdo1(0x0F, torques))
        syncs += 1
        trajectory.append(positions(tpdos) + velocities(tpdos))
    tpdos = master.cycle(rpdo1(0x0F, profile(1000)))          # the state after the last profile cycle
    syncs += 1
    commands.append(profile(1000))
    trajectory.append(positions(tpdos) + velocities(tpdos))
    check(all(s & 0x6F == 0x27 for s in statuswords(tpdos)), "1000 CST cycles: still operation enabled")
    moved = max(abs(row[0] - trajectory[0][0]) for row in trajectory)
    check(moved > 1000, "the torque profile moved joint 1 (%d urad)" % moved)

    with open(os.path.join(work, "commands.txt"), "w") as f:
        f.write("start %d\n" % start)
        for row in commands[:-1]:
            f.write(" ".join(map(str, row)) + "\n")
    expected_rows = subprocess.run([reference, os.path.join(work, "commands.txt")], check=True, capture_output=True, text=True).stdout.split("\n")
    expected_rows = [list(map(int, r.split())) for r in expected_rows if r.strip()]
    # The reference's row i is the state after cycle start + i, sent in the TPDOs of SYNC
    # start + i + 1; the trajectory begins with the TPDOs of SYNC start + 2.
    wire = expected_rows[1:]
    same = sum(1 for a, b in zip(wire, trajectory) if a == b)
    check(len(wire) == len(trajectory) and same == len(trajectory),
          "CST trajectory on the wire equals the in-process emulator bit for bit (%d of %d cycles, 7 positions + 7 velocities)" % (same, len(trajectory)))

    # RPDO silence: SYNCs without RPDOs; the 20th lost cycle is communication_constraints_violation.
    master.emcy.clear()
    lost = 0
    while lost < 25 and not master.emcy:
        tpdos = master.cycle([])
        lost += 1
        master.wait_for(lambda m: 0x081 <= m.arbitration_id <= 0x087, timeout=0.05)   # the cycle's EMCY, if any
    master.wait_for(lambda m: False, timeout=0.2)
    codes = {(node, code) for node, code, _, _ in master.emcy}
    check(lost == 20, "EMCY after 20 silent cycles (after %d)" % lost)
    check(codes == {(n, 0x8250) for n in NODES}, "EMCY 0x8250 (RPDO timeout = communication_constraints_violation) from every node: %s" % sorted(codes))
    check(all(node_reg & 0x11 == 0x11 for _, _, node_reg, _ in master.emcy), "EMCY error register: generic + communication")
    tpdos = master.cycle([])
    check(all(s & 0x4F == 0x0F for s in statuswords(tpdos)), "every drive in 402 fault reaction active (statusword & 0x4F = 0x0F)")
    tpdos = master.cycle([])
    check(all(s & 0x4F == 0x08 for s in statuswords(tpdos)), "then in 402 fault (statusword & 0x4F = 0x08)")
    check(master.upload(4, 0x2002, 32) == b"\x01", "0x2002 sub 32 (communication_constraints_violation) = 1")
    # Fault reset: rising edge of controlword bit 7 -> automatic error recovery -> switch on disabled.
    master.emcy.clear()
    master.cycle(rpdo1(0x80))
    tpdos = master.cycle(rpdo1(0x00))
    check(all(s & 0x4F == 0x40 for s in statuswords(tpdos)), "fault reset -> switch on disabled (statusword & 0x4F = 0x40)")
    check({(n, c) for n, c, _, _ in master.emcy} == {(n, 0x0000) for n in NODES}, "EMCY 0x0000 (error reset) from every node")
    check(master.upload(4, 0x2002, 32) == b"\x00", "error recovered: 0x2002 sub 32 = 0")
    # Enable again and hold: the robot moves again after the recovery.
    for controlword in (0x06, 0x07, 0x0F, 0x0F):
        tpdos = master.cycle(rpdo1(controlword))
    check(all(s & 0x6F == 0x27 for s in statuswords(tpdos)), "operation enabled again after the recovery")
    text = stop_serve(serve, work, "session")
    check("motions 2" in text and "error recoveries 1" in text, "serve counted 2 motions and 1 error recovery")

    replay = subprocess.run([csp, "replay", log, "--csv", replayed_csv], capture_output=True, text=True)
    print(replay.stdout + replay.stderr, flush=True)
    check(replay.returncode == 0 and "bit for bit" in replay.stdout, "csp replay re-simulates the CAN session log bit for bit")
    with open(csv) as served, open(replayed_csv) as replayed:
        rows = served.read()
        check(rows.count("\n") > 1000 and rows == replayed.read(),
              "the --csv log of the served robot (%d lines) is the re-simulated run's, row for row" % rows.count("\n"))


def badinput(csp, work):
    # The flood's COB-ID 0x3FF (TPDO3 of node 127: no node of CSP's) is filtered out here, so
    # that this master keeps up while CSP reads the 1e5 frames.
    master = Master()
    master.bus.set_filters([{"can_id": base, "can_mask": 0x780} for base in (0x080, 0x180, 0x280, 0x580, 0x700)])
    log = os.path.join(work, "badinput.lcmlog")
    serve = boot(master, csp, work, "badinput", "--log", log)
    master.send(0x000, [0x01, 0x00])

    master.emcy.clear()
    master.send(0x202, [0x0F])                                # RPDO1 of node 2 with 1 byte of its 4
    master.wait_for(lambda m: m.arbitration_id == 0x082, timeout=2)
    check((2, 0x8210) in [(n, c) for n, c, _, _ in master.emcy], "RPDO shorter than its mapping: EMCY 0x8210 (PDO length)")
    master.send(0x3FF, b"\x01\x02")                            # unknown COB-IDs: ignored, no answer
    master.send(0x6FF, bytes(8))
    check(master.wait_for(lambda m: m.arbitration_id == 0x5FF, timeout=0.3) is None, "SDO to a node that is not there: no answer")

    def abort_code(node, command, index, sub, value):
        try:
            master._sdo_request(node, struct.pack("<BHB", command, index, sub) + value)
            return None
        except SdoAbort as e:
            return e.code
    check(abort_code(1, 0x2F, 0x6060, 0, bytes([3, 0, 0, 0])) in (0x06090030, 0x06090031, 0x06090032), "0x6060 = 3 (no such mode): abort 0x0609003x")
    check(abort_code(1, 0x2B, 0x6072, 0, struct.pack("<H", 60000) + bytes(2)) == 0x06090031, "0x6072 max torque beyond tau_max: abort 0x06090031")
    check(abort_code(1, 0x23, 0x1000, 0, bytes(4)) == 0x06010002, "write to the const 0x1000: abort 0x06010002")
    check(abort_code(1, 0x23, 0x6040, 0, bytes(4)) == 0x06070012, "4 bytes to the U16 controlword: abort 0x06070012")
    # CiA 301 7.3.5: no PDO or EMCY on a restricted CAN-ID or the SYNC's; a valid one is not moved.
    cob = lambda value: struct.pack("<I", value)
    check(abort_code(5, 0x23, 0x1800, 1, cob(0x190)) == 0x06090030, "TPDO1 moved while valid: abort 0x06090030 (set bit 31 first)")
    check(abort_code(5, 0x23, 0x1800, 1, cob(0x80000185)) is None, "TPDO1 switched off (bit 31)")
    refused = {cob_id: abort_code(5, 0x23, 0x1800, 1, cob(cob_id)) for cob_id in (0x000, 0x080, 0x585, 0x605, 0x705, 0x7FF)}
    check(set(refused.values()) == {0x06090030}, "TPDO1 on NMT, SYNC, SDO, heartbeat, reserved ids: abort 0x06090030 (%s)" %
          ", ".join("0x%03X: %s" % (i, "accepted" if c is None else "0x%08X" % c) for i, c in refused.items()))
    check(abort_code(5, 0x23, 0x1800, 1, cob(0x185)) is None, "TPDO1 back on 0x185")
    check(abort_code(5, 0x23, 0x1014, 0, cob(0x80000085)) is None and abort_code(5, 0x23, 0x1014, 0, cob(0x000)) == 0x06090030
          and abort_code(5, 0x23, 0x1014, 0, cob(0x085)) is None, "EMCY: off, NMT id refused (0x06090030), back on 0x085")

    # An out-of-range target torque: limited to 0x6072, a jump all the same -> the robot's reflex.
    for controlword in (0x06, 0x07, 0x0F, 0x0F):
        master.cycle(rpdo1(controlword))
    master.emcy.clear()
    master.cycle(rpdo1(0x0F, [0x7FFF, 0, 0, 0, 0, 0, 0]))
    master.wait_for(lambda m: False, timeout=0.3)
    check({(n, c) for n, c, _, _ in master.emcy} >= {(n, 0xFF1E) for n in NODES},
          "target torque 0x7FFF: limited, still a jump: EMCY 0xFF1E controller_torque_discontinuity from every node")
    master.cycle(rpdo1(0x00))
    tpdos = master.cycle(rpdo1(0x80))
    tpdos = master.cycle(rpdo1(0x00))
    check(all(s & 0x4F == 0x40 for s in statuswords(tpdos)), "fault reset after the reflex -> switch on disabled")

    # A flood of 1e5 frames while the arm is in a CST motion: every cycle is answered, none lost.
    for controlword in (0x06, 0x07, 0x0F):
        master.cycle(rpdo1(controlword))
    flood = subprocess.Popen(["cangen", "vcan0", "-I", "3FF", "-L", "8", "-D", "i", "-g", "0", "-n", "100000"])
    flood_cycles = 0
    while flood.poll() is None:
        tpdos = master.cycle(rpdo1(0x0F), timeout=120)   # CSP reads the flood's frames queued before each SYNC
        flood_cycles += 1
    for _ in range(20):
        tpdos = master.cycle(rpdo1(0x0F))
    check(flood.returncode == 0, "cangen sent 1e5 frames on COB-ID 0x3FF")
    check(all(s & 0x6F == 0x27 for s in statuswords(tpdos)), "after the flood (%d cycles during it): still operation enabled" % flood_cycles)
    # A flood into a stopped server: its socket's queue fills, the kernel drops the rest, and the
    # report counts them (SO_RXQ_OVFL), and the queued ones as late (handled > 1 ms after they came).
    master.cycle(rpdo1(0x07))                                  # disable operation: the motion ends, nothing is lost meanwhile
    serve.send_signal(signal.SIGSTOP)
    stopped_flood = subprocess.run(["cangen", "vcan0", "-I", "3FF", "-L", "8", "-D", "i", "-g", "0", "-n", "50000"])
    while master.recv(0) is not None:                          # what the master had not read yet
        pass
    serve.send_signal(signal.SIGCONT)
    # The server reads its whole queue before it next sends a heartbeat (100 ms idle): a request sent
    # before that could find the queue still full and be dropped too.
    heartbeat = master.wait_for(lambda m: 0x701 <= m.arbitration_id <= 0x707, timeout=120)
    answered = heartbeat is not None and master.upload(1, 0x1000, 0) == struct.pack("<I", 0x00020192)
    check(stopped_flood.returncode == 0 and answered, "5e4 frames into the stopped server, then it answers an SDO request")
    text = stop_serve(serve, work, "badinput")
    lost = int(text.split("lost commands ")[1].split()[0])
    ignored = int(text.split("ignored frames ")[1].split(",")[0])
    dropped = int(re.search(r"dropped (\d+) \(receive queue full\)", text).group(1))
    late = int(re.search(r"late (\d+) \(handled", text).group(1))
    check(lost == 0, "no command lost during the flood (lost commands %d)" % lost)
    check(dropped > 0 and ignored + dropped == 150002,
          "every flood frame is accounted for: %d handled (ignored) + %d dropped by the kernel (receive queue full) = 100000 + 50000 + 2 unknown" % (ignored, dropped))
    check(late >= 1000, "frames queued while the server was stopped counted late: %d" % late)
    check("frames dropped: the socket's receive queue was full" in text, "the report warns of the dropped frames")
    with open(log, "rb") as f:
        check(b"dropped %d (receive queue full)" % dropped in f.read(), "the session log has the frame counts (received, dropped, late)")
    replay = subprocess.run([csp, "replay", log], capture_output=True, text=True)
    print(replay.stdout + replay.stderr, flush=True)
    check(replay.returncode == 0 and "bit for bit" in replay.stdout, "the log of the bad-input session is complete: csp replay bit for bit")


# --- the stateful fuzz: random sequences against the live server, invariants after each step ---
def restricted(cob_id):
    """CiA 301 7.3.5 "restricted CAN-IDs" (written from its table)."""
    return (cob_id <= 0x07F or 0x101 <= cob_id <= 0x180 or 0x581 <= cob_id <= 0x5FF or 0x601 <= cob_id <= 0x67F
            or 0x6E0 <= cob_id <= 0x6FF or cob_id >= 0x701)


# docs/can.md's EMCY table: the communication codes, mixed modes, targets ignored, libfranka's errors.
EMCY_CODES = {0x0000, 0x8130, 0x8210, 0x8220, 0x8240, 0x8250, 0x6320, 0xFF00} | set(range(0xFF01, 0xFF2A))
# A node's COB-ID objects (index, sub-index) and their default function codes (+ node id, valid).
COB_OBJECTS = {(0x1014, 0): 0x080, (0x1400, 1): 0x200, (0x1401, 1): 0x300, (0x1402, 1): 0x400,
               (0x1403, 1): 0x500, (0x1800, 1): 0x180, (0x1801, 1): 0x280}
TPDO_OBJECTS = [(0x1800, 1), (0x1801, 1)]
MAPPABLE = {True: [(0x6040, 16), (0x6071, 16), (0x607A, 32), (0x60FF, 32), (0x60B2, 16), (0x6060, 8)],          # RPDO
            False: [(0x6041, 16), (0x6064, 32), (0x606C, 32), (0x6077, 16), (0x6061, 8), (0x2001, 16), (0x1001, 8)]}
PDO_ABORTS = {0x06040041, 0x06040042, 0x06040043, 0x06090030, 0x08000022}


class Fuzz:
    """A model of what the master configured (each node's COB-IDs, NMT state), random steps, and
    the invariants: no frame from CSP on a restricted CAN-ID or the SYNC's, every frame on an id
    the model says is in use, EMCY codes documented; a COB-ID write accepted exactly when CiA 301
    allows it; every SYNC answered by the TPDOs in use; statusword bit 12 ("follows the target")
    only in operation enabled, after a cycle only with all seven enabled in one mode, and a drive
    that loses it while staying enabled sends EMCY 0xFF00."""

    def __init__(self, master, rng):
        self.m, self.rng = master, rng
        self.frames = []
        self.cob = {}
        self.nmt = {}
        self.cw = {n: 0x0F for n in NODES}
        self.followed = {n: False for n in NODES}
        for n in NODES:
            self.reset_node_model(n)
        self.ids_before = self.ids_in_use()

    def reset_node_model(self, n):
        for key, function in COB_OBJECTS.items():
            self.cob[(n,) + key] = function + n
        self.nmt[n] = "pre"

    def recv_all(self, timeout):
        msg = self.m.recv(timeout)
        while msg is not None:
            self.frames.append(msg)
            msg = self.m.recv(0)

    def ids_in_use(self):
        ids = {0x580 + n for n in NODES} | {0x700 + n for n in NODES}
        for (n, index, sub), value in self.cob.items():
            if not value & 0x80000000 and (index == 0x1014 or index >= 0x1800):
                ids.add(value & 0x7FF)
        return ids

    def sdo(self, node, index, sub, value, size):
        """Expedited download; the abort code or None. Frames seen meanwhile are kept."""
        command = 0x23 | (4 - size) << 2
        self.m.send(0x600 + node, struct.pack("<BHB", command, index, sub) + value.to_bytes(4, "little"))
        data = self.sdo_reply(node)
        return struct.unpack_from("<I", data, 4)[0] if data[0] == 0x80 else None

    def upload16(self, node, index):
        """Expedited upload of a 16-bit object; None when aborted."""
        self.m.send(0x600 + node, struct.pack("<BHB4x", 0x40, index, 0))
        data = self.sdo_reply(node)
        return struct.unpack_from("<H", data, 4)[0] if data[0] != 0x80 else None

    def sdo_reply(self, node):
        """The node's next SDO response (its 8 data bytes); frames seen meanwhile are kept."""
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            msg = self.m.recv(max(0.0, deadline - time.monotonic()))
            if msg is None:
                continue
            self.frames.append(msg)
            if msg.arbitration_id == 0x580 + node:
                return bytes(msg.data)
        raise TimeoutError("no SDO answer from node %d" % node)

    # --- steps
    def step_nmt(self):
        command = self.rng.choice([0x01, 0x01, 0x80, 0x02, 0x81, 0x82])
        node = self.rng.choice([0] + list(NODES))
        targets = list(NODES) if node == 0 else [node]
        self.m.send(0x000, [command, node])
        if command in (0x81, 0x82):                       # boot-up, then pre-operational
            booted = set()
            deadline = time.monotonic() + 5
            while booted != set(targets) and time.monotonic() < deadline:
                msg = self.m.recv(0.1)
                if msg is not None:
                    self.frames.append(msg)
                    if msg.arbitration_id - 0x700 in targets and bytes(msg.data) == b"\x00":
                        booted.add(msg.arbitration_id - 0x700)
            check(booted == set(targets), "fuzz: NMT reset 0x%02X of node %d: boot-up from %s" % (command, node, sorted(booted)), quiet=True)
            for n in targets:
                self.reset_node_model(n)                  # both restore the COB-IDs (0x1000-0x1FFF)
        else:
            for n in targets:
                self.nmt[n] = {0x01: "op", 0x80: "pre", 0x02: "stopped"}[command]
        if command == 0x02:                               # stopped answers no SDO: back to operational
            self.m.send(0x000, [0x01, node])
            for n in targets:
                self.nmt[n] = "op"

    def cob_value(self, n, key):
        choice = self.rng.random()
        if choice < 0.4:
            cob_id = self.rng.choice([0x000, 0x001, 0x07F, 0x080, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F,
                                      0x6E0, 0x6FF, 0x701, 0x77F, 0x780, 0x7FF])
        elif choice < 0.8:
            cob_id = self.rng.choice([0x100, 0x190 + n, 0x1F0 + n, 0x3F0 + n, 0x580, 0x600, 0x680 + n, 0x6D0 + n, 0x700])
        else:
            cob_id = COB_OBJECTS[key] + n
        return cob_id | (0x80000000 if self.rng.random() < 0.5 else 0)

    def step_cob(self):
        n = self.rng.choice(list(NODES))
        key = self.rng.choice(list(COB_OBJECTS))
        value = self.cob_value(n, key)
        current = self.cob[(n,) + key]
        cob_id = value & 0x7FF
        allowed = bool(value & 0x80000000) or ((current & 0x80000000 or value == current)
                                               and not restricted(cob_id) and cob_id != 0x080)
        code = self.sdo(n, key[0], key[1], value, 4)
        check((code is None) == allowed and code in (None, 0x06090030),
              "fuzz: node %d 0x%04X:%d 0x%03X -> 0x%08X (was 0x%08X): %s, CiA 301 says %s" %
              (n, key[0], key[1], cob_id, value, current, "accepted" if code is None else "abort 0x%08X" % code,
               "accept" if allowed else "refuse"), quiet=True)
        if code is None:
            self.cob[(n,) + key] = value

    def step_remap(self):
        n = self.rng.choice(list(NODES))
        key = self.rng.choice([k for k in COB_OBJECTS if k[0] != 0x1014])
        receive = key[0] < 0x1800
        current = self.cob[(n,) + key]
        entries = [self.rng.choice(MAPPABLE[receive]) for _ in range(self.rng.randint(0, 3))]
        stop_after = self.rng.randint(1, 5) if self.rng.random() < 0.2 else 99
        requests = [(key[0], 1, current | 0x80000000, 4), (key[0] + 0x200, 0, 0, 1)]
        requests += [(key[0] + 0x200, i + 1, index << 16 | bits, 4) for i, (index, bits) in enumerate(entries)]
        requests += [(key[0] + 0x200, 0, len(entries), 1), (key[0], 1, current & 0x7FFFFFFF, 4)]
        for i, (index, sub, value, size) in enumerate(requests[:stop_after]):
            code = self.sdo(n, index, sub, value, size)
            check(code is None or code in PDO_ABORTS, "fuzz: remap node %d 0x%04X:%d = 0x%X: %s" %
                  (n, index, sub, value, "ok" if code is None else "abort 0x%08X" % code), quiet=True)
            if index == key[0] and code is None:
                self.cob[(n,) + key] = value

    def step_controlword(self):
        cw = self.rng.choice([0x06, 0x07, 0x0F, 0x0F, 0x0F, 0x00, 0x02, 0x80])
        targets = list(NODES) if self.rng.random() < 0.5 else [self.rng.choice(list(NODES))]
        for n in targets:
            self.cw[n] = cw
            check(self.sdo(n, 0x6040, 0, cw, 2) is None, "fuzz: controlword 0x%02X to node %d" % (cw, n), quiet=True)

    def step_mode(self):
        mode = self.rng.choice([8, 9, 10, 10, 3])
        targets = list(NODES) if self.rng.random() < 0.7 else [self.rng.choice(list(NODES))]
        for n in targets:
            code = self.sdo(n, 0x6060, 0, mode, 1)
            check((code is None) == (mode != 3), "fuzz: mode %d to node %d: %s" % (mode, n, code), quiet=True)

    def step_cycles(self):
        for _ in range(self.rng.randint(1, 25)):
            expected = {}
            for n in NODES:
                if self.nmt[n] != "op":
                    continue
                rpdo1 = self.cob[(n, 0x1400, 1)]
                if not rpdo1 & 0x80000000:
                    self.m.send(rpdo1 & 0x7FF, struct.pack("<Hh", self.cw[n], 0))
                for key in TPDO_OBJECTS:
                    value = self.cob[(n,) + key]
                    if not value & 0x80000000:
                        expected[value & 0x7FF] = expected.get(value & 0x7FF, 0) + 1
            self.m.send(0x080)
            got = {}
            deadline = time.monotonic() + 10
            while any(got.get(i, 0) < c for i, c in expected.items()) and time.monotonic() < deadline:
                msg = self.m.recv(max(0.0, deadline - time.monotonic()))
                if msg is not None:
                    self.frames.append(msg)
                    got[msg.arbitration_id] = got.get(msg.arbitration_id, 0) + 1
            check(all(got.get(i, 0) >= c for i, c in expected.items()),
                  "fuzz: SYNC answered by the TPDOs in use %s (got %s)" % (expected, got), quiet=True)

    # --- invariants
    def check_step(self, name, after_cycles):
        self.recv_all(0.02)
        ids = self.ids_in_use() | self.ids_before
        for msg in self.frames:
            cob_id, data = msg.arbitration_id, bytes(msg.data)
            ours = cob_id in (0x580 + n for n in NODES) or cob_id in (0x700 + n for n in NODES)
            check(cob_id != 0x080 and (ours or not restricted(cob_id)),
                  "fuzz %s: frame on a restricted id or the SYNC's: %03X#%s" % (name, cob_id, data.hex()), quiet=True)
            check(cob_id in ids, "fuzz %s: frame on an id nothing uses: %03X#%s (in use: %s)" %
                  (name, cob_id, data.hex(), sorted(map(hex, ids))), quiet=True)
            for n in NODES:
                emcy = self.cob[(n, 0x1014, 0)]
                if not emcy & 0x80000000 and cob_id == emcy & 0x7FF and len(data) == 8 and data[4] == n:
                    code = data[0] | data[1] << 8
                    check(code in EMCY_CODES, "fuzz %s: EMCY 0x%04X of node %d is documented" % (name, code, n), quiet=True)
        emcy_ff00 = {bytes(m.data)[4] for m in self.frames if len(m.data) == 8 and bytes(m.data)[:2] == b"\x00\xFF"}
        words = {n: self.upload16(n, 0x6041) for n in NODES}
        modes = {n: self.upload16(n, 0x6061) & 0xFF for n in NODES} if after_cycles else {}
        for n, word in words.items():
            followed = bool(word & 0x1000)
            check(not followed or word & 0x6F == 0x27, "fuzz %s: bit 12 only in operation enabled (node %d: 0x%04X)" % (name, n, word), quiet=True)
            if after_cycles:
                check(not followed or (all(w & 0x6F == 0x27 for w in words.values()) and len(set(modes.values())) == 1),
                      "fuzz %s: bit 12 of node %d with all seven enabled in one mode (%s, modes %s)" %
                      (name, n, ["0x%04X" % w for w in words.values()], modes), quiet=True)
                if self.followed[n] and not followed and word & 0x6F == 0x27:
                    check(n in emcy_ff00, "fuzz %s: node %d stays enabled with its target no longer followed: EMCY 0xFF00" % (name, n), quiet=True)
            self.followed[n] = followed if after_cycles else self.followed[n] and followed
        self.frames = []
        self.ids_before = self.ids_in_use()


def fuzz(csp, work, steps, seed):
    seed = int(seed) if seed else int(time.time())
    print("fuzz: seed %d (master.py fuzz CSP WORK %s %d repeats this run)" % (seed, steps, seed), flush=True)
    rng = random.Random(seed)
    master = Master()
    log = os.path.join(work, "fuzz.lcmlog")
    serve = boot(master, csp, work, "fuzz", "--log", log)
    f = Fuzz(master, rng)
    master.send(0x000, [0x01, 0x00])
    for n in NODES:
        f.nmt[n] = "op"
    kinds = [("nmt", f.step_nmt, 1), ("cob", f.step_cob, 4), ("remap", f.step_remap, 2),
             ("controlword", f.step_controlword, 3), ("mode", f.step_mode, 1), ("cycles", f.step_cycles, 5)]
    counts = {name: 0 for name, _, _ in kinds}
    failed_before = len(failures)
    started = time.monotonic()
    done = 0
    while done < int(steps) and time.monotonic() - started < 25 and len(failures) == failed_before:
        name, run, _ = rng.choices(kinds, weights=[w for _, _, w in kinds])[0]
        run()
        f.check_step("step %d (%s)" % (done, name), name == "cycles")
        counts[name] += 1
        done += 1
    check(len(failures) == failed_before, "fuzz: %d steps in %.0f s, invariants held after each (%s)" %
          (done, time.monotonic() - started, counts))
    stop_serve(serve, work, "fuzz")
    replay = subprocess.run([csp, "replay", log], capture_output=True, text=True)
    check(replay.returncode == 0 and "bit for bit" in replay.stdout, "fuzz: the session log re-simulates bit for bit")


def busload(work):
    """canbusload's worst-case figures (summed over its 1 s lines) vs csp can serve's own count."""
    frames = bits = 0
    for line in open(os.path.join(work, "busload.txt")):
        fields = line.split()
        if fields and fields[0] == "vcan0@1000000":
            frames += int(fields[1])
            bits += int(fields[2])
    text = open(os.path.join(work, "session.out")).read()
    csp = text.split("vcan0 (joints 1,2,3,4,5,6,7): ")[1]
    csp_frames, csp_bits = int(csp.split(" frames")[0]), int(csp.split("frames, ")[1].split(" bits")[0])
    check(frames > 10000 and (frames, bits) == (csp_frames, csp_bits),
          "canbusload: %d frames, %d bits; csp can serve: %d frames, %d bits (worst-case stuffing)" % (frames, bits, csp_frames, csp_bits))


def replay_compare(work):
    """The TPDOs of a canplayer replay of the master's frames equal those of the session."""
    def tpdos(path):
        out = []
        for line in open(os.path.join(work, path)):
            frame = line.split()[2]
            if frame[:3] in ("181", "182", "183", "184", "185", "186", "187", "281", "282", "283", "284", "285", "286", "287"):
                out.append(frame)
        return out
    original, replayed = tpdos("session.candump"), tpdos("replay.candump")
    first = next((i for i, (a, b) in enumerate(zip(original, replayed)) if a != b), None)
    check(len(replayed) >= 14 * 90 and first is None,
          "candump -L -> canplayer -> the same TPDO stream (%d TPDOs; first difference: %s)" %
          (len(replayed), None if first is None else (first, original[first], replayed[first])))


def master_frames(work, syncs):
    """The master's frames of the session (NMT, SYNC, RPDOs, SDO requests) up to its n-th SYNC."""
    with open(os.path.join(work, "session.candump")) as f, open(os.path.join(work, "master.candump"), "w") as out:
        count = 0
        for line in f:
            cob = int(line.split()[2].split("#")[0], 16)
            if cob in (0x000, 0x080) or cob & 0x780 in (0x200, 0x300, 0x400, 0x500, 0x600):   # NMT, SYNC, RPDO1-4, SDO requests
                out.write(line)
                count += cob == 0x080
                if count == syncs:
                    break


def split(work):
    """With --split 4 each node's frames are on its own bus: joints 1-2 vcan0, 3-4 vcan1, 5-6 vcan2, 7 vcan3."""
    bus_of_node = {1: "vcan0", 2: "vcan0", 3: "vcan1", 4: "vcan1", 5: "vcan2", 6: "vcan2", 7: "vcan3"}
    wrong, tpdos, syncs = [], 0, {}
    for line in open(os.path.join(work, "split.candump")):
        _, iface, frame = line.split()
        cob = int(frame.split("#")[0], 16)
        if cob == 0x080:
            syncs[iface] = syncs.get(iface, 0) + 1
        elif cob & 0x7F in bus_of_node and cob & 0x780 in (0x180, 0x280, 0x700):
            tpdos += cob & 0x780 != 0x700
            if bus_of_node[cob & 0x7F] != iface:
                wrong.append(line.strip())
    check(not wrong and tpdos > 100, "every node's TPDOs and heartbeats on its own bus (%d TPDOs; misplaced: %s)" % (tpdos, wrong[:3]))
    text = open(os.path.join(work, "split.out")).read()
    sent = int(re.search(r"SYNCs (\d+)", text).group(1))
    check(sorted(syncs) == ["vcan0", "vcan1", "vcan2", "vcan3"] and set(syncs.values()) == {sent},
          "CSP's %d SYNCs on each of the four buses: %s" % (sent, syncs))
    loads = [float(part.split(" %")[0]) for part in text.split("1 kHz: ")[1:]]
    check(len(loads) == 4 and all(0 < load < 100 for load in loads), "load per bus at 1 Mbit/s under 100 %%: %s" % loads)


def main():
    os.sched_setaffinity(0, {min(ALL_CPUS)})
    command = sys.argv[1]
    if command == "session":
        session(*sys.argv[2:5])
    elif command == "badinput":
        badinput(*sys.argv[2:4])
    elif command == "fuzz":
        fuzz(sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5] if len(sys.argv) > 5 else None)
    elif command == "busload":
        busload(sys.argv[2])
    elif command == "master-frames":
        master_frames(sys.argv[2], int(sys.argv[3]))
    elif command == "split":
        split(sys.argv[2])
    elif command == "replay-compare":
        replay_compare(sys.argv[2])
    else:
        raise SystemExit("unknown command " + command)
    if failures:
        print("%d check(s) failed:" % len(failures))
        for f in failures:
            print("  " + f)
        sys.exit(1)


if __name__ == "__main__":
    main()
