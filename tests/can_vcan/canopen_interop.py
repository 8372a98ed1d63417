#!/usr/bin/python3
"""Interop: the unmodified python-canopen (shared/vendor, MIT; its BaseNode402 CiA 402 master)
drives `csp can serve` inside the sandbox's guest kernel, run as a user runs a master
(`csp-can-sandbox --here -- canopen_interop.py ...`: the sandbox starts the server), with the
timeouts docs/can.md gives for the guest: it reads the start pose by SDO before any SYNC,
loads CSP's EDS, maps the PDOs by SDO as a CiA 302 master does, starts the nodes, walks the 402
state machine with its own `state` setter, sets the modes with its `op_mode` setter and moves the
arm in CSP and then CST mode. On the way: a PDO on a restricted CAN-ID is refused, and when one
drive leaves operation enabled the others say (EMCY 0xFF00, statusword bit 12) that their targets
are ignored. Its cyclic part is a master's usual cycle thread: every RPDO, then
one SYNC.

  canopen_interop.py CSP VENDOR WORK
"""
import math
import os
import subprocess
import sys
import threading
import time

failures = []
# The timeouts docs/can.md gives for python-canopen in the sandbox's guest [s].
SDO_RESPONSE_TIMEOUT = 5.0
STATE_TIMEOUT = 10.0


def check(condition, what):
    print(("ok    " if condition else "FAIL  ") + what, flush=True)
    if not condition:
        failures.append(what)


def main(csp, vendor, work):
    sys.path.insert(0, os.path.join(vendor, "python-canopen"))
    import canopen

    network = canopen.Network()
    network.connect(channel="vcan0", interface="socketcan")
    emcy = []
    nodes = []
    for n in range(1, 8):
        eds = os.path.join(work, "joint%d.eds" % n)
        subprocess.run([csp, "can", "eds", "--node", str(n), "-o", eds], check=True)
        node = canopen.BaseNode402(n, eds)
        network.add_node(node)
        # docs/can.md, "Your own master without kernel CAN": python-canopen's defaults (0.2 to
        # 0.8 s) are shorter than an emulated guest's stalls on a busy machine.
        node.sdo.RESPONSE_TIMEOUT = SDO_RESPONSE_TIMEOUT
        node.TIMEOUT_SWITCH_OP_MODE = node.TIMEOUT_SWITCH_STATE_SINGLE = node.TIMEOUT_CHECK_TPDO = STATE_TIMEOUT
        node.TIMEOUT_SWITCH_STATE_FINAL = node.TIMEOUT_RESET_FAULT = STATE_TIMEOUT
        node.emcy.add_callback(lambda e, n=n: emcy.append((n, e.code)))
        nodes.append(node)
    states = [node.nmt.wait_for_heartbeat(10) for node in nodes]
    check(states == ["PRE-OPERATIONAL"] * 7, "python-canopen: the seven nodes are up (heartbeats: %s)" % states)
    # Before any SYNC the drives report the robot's pose: the scenario's start (libfranka's
    # "ready" pose, joint 2 at -0.785398 rad, joint 4 at -2.356194 rad), not 0.
    ready = [0, -785398, 0, -2356194, 0, 1570796, 785398]
    check([node.sdo[0x6064].raw for node in nodes] == ready, "0x6064 by SDO before the first SYNC: the start pose in urad")

    # CiA 301 7.3.5: a PDO may not be switched on at a restricted CAN-ID (NMT 0x000, SDO, heartbeat,
    # ...) nor the SYNC's 0x080: python-canopen's SDO client gets abort 0x06090030.
    tpdo1_cob = nodes[0].sdo[0x1800][1]
    tpdo1_cob.raw = 0x80000181                                  # switched off first (bit 31)
    codes = {}
    for cob_id in (0x000, 0x080, 0x581, 0x701):
        try:
            tpdo1_cob.raw = cob_id
            codes[cob_id] = None
        except canopen.SdoAbortedError as e:
            codes[cob_id] = e.code
    check(set(codes.values()) == {0x06090030}, "TPDO1 on NMT, SYNC, SDO, heartbeat ids: abort 0x06090030 (%s)" %
          {hex(k): None if v is None else hex(v) for k, v in codes.items()})
    tpdo1_cob.raw = 0x181

    # PDO mapping by SDO (COB-ID invalid, count 0, entries, count, COB-ID valid).
    for node in nodes:
        node.pdo.read()
        rpdo, tpdo1, tpdo2 = node.rpdo[1], node.tpdo[1], node.tpdo[2]
        rpdo.clear()
        rpdo.add_variable(0x6040)   # controlword
        rpdo.add_variable(0x607A)   # target position
        rpdo.add_variable(0x6071)   # target torque
        rpdo.trans_type, rpdo.enabled = 1, True
        tpdo1.clear()
        tpdo1.add_variable(0x6041)  # statusword
        tpdo1.add_variable(0x6064)  # position actual value
        tpdo1.trans_type, tpdo1.enabled = 1, True
        tpdo2.clear()
        tpdo2.add_variable(0x6061)  # modes of operation display
        tpdo2.add_variable(0x606C)  # velocity actual value
        tpdo2.trans_type, tpdo2.enabled = 1, True
        for disabled in (2, 3, 4):
            node.rpdo[disabled].enabled = False
        node.pdo.save()
        node.setup_402_state_machine(read_pdos=True)
    check(all(n.rpdo[1].length == 64 for n in nodes), "RPDO1 remapped by SDO: controlword + target position + target torque (8 bytes)")

    # The master's cycle thread: every RPDO1, then SYNC, then wait for the TPDOs; `on_cycle` sets
    # the targets.
    stop = threading.Event()
    on_cycle = [lambda k: None]
    cycles = [0]

    def cycle_thread():
        while not stop.is_set():
            on_cycle[0](cycles[0])
            last = nodes[6].tpdo[2]          # the last TPDO the drives send after a SYNC
            answered = last.timestamp
            for node in nodes:
                node.rpdo[1].transmit()
            network.sync.transmit()
            # Lockstep: the next cycle once the drives answered this SYNC.
            deadline = time.monotonic() + 10
            while last.timestamp == answered and time.monotonic() < deadline:
                time.sleep(0.0005)
            cycles[0] += 1

    network.nmt.state = "OPERATIONAL"
    thread = threading.Thread(target=cycle_thread)
    thread.start()

    def wait_cycles(n):
        end = cycles[0] + n
        while cycles[0] < end and thread.is_alive():
            time.sleep(0.01)

    def position(node):
        node.tpdo[1].wait_for_reception(10)
        return node.tpdo_values[0x6064]

    try:
        wait_cycles(3)
        # CSP: the targets start at the robot's desired position 0x6062 (q_d), where libfranka's
        # motion generators start (the measured q may differ while the robot holds it).
        start = [node.sdo[0x6062].raw for node in nodes]
        for node, q in zip(nodes, start):
            node.rpdo[1]["Target position"].raw = q
            node.op_mode = "CYCLIC SYNCHRONOUS POSITION"
        check(all(n.op_mode == "CYCLIC SYNCHRONOUS POSITION" for n in nodes), "op_mode CSP (0x6060 by SDO, 0x6061 by TPDO)")
        for node in nodes:
            node.state = "OPERATION ENABLED"
        check(all(n.state == "OPERATION ENABLED" for n in nodes), "BaseNode402.state = OPERATION ENABLED on every node")
        # Joint 1: +4000 urad along a cosine in 400 cycles (jerk about 1 rad/s^3 plus the 1 urad
        # quantization's, inside the Panda's 7500 rad/s^3). The
        # plant's static friction stops the robot's joint impedance (600 N m/rad) anywhere within
        # breakaway / stiffness = 0.245 / 600 = 408 urad of the target, as a real joint sticks.
        moved_from = cycles[0]

        def csp_cycle(k):
            step = min(max(k - moved_from, 0), 400)
            nodes[0].rpdo[1]["Target position"].raw = start[0] + round(2000 * (1 - math.cos(math.pi * step / 400)))
        on_cycle[0] = csp_cycle
        wait_cycles(500)
        q1 = position(nodes[0])
        check(abs(q1 - (start[0] + 4000)) < 450, "CSP: joint 1 followed +4000 urad (at %+d urad)" % (q1 - start[0]))
        check(not emcy, "no EMCY during the CSP motion: %s" % emcy)
        check(all(node.statusword & 0x1000 for node in nodes), "statusword bit 12 (the drive follows its target) on every drive during the motion")

        # Joint 1 leaves operation enabled first: the motion ends, and the six drives still in
        # operation enabled clear bit 12 and send EMCY 0xFF00 (their targets are ignored now).
        nodes[0].state = "SWITCHED ON"
        wait_cycles(3)
        check(sorted(emcy) == [(n, 0xFF00) for n in range(2, 8)], "joint 1 left: EMCY 0xFF00 from drives 2-7: %s" % sorted(emcy))
        check(all(n.state == "OPERATION ENABLED" and not n.statusword & 0x1000 for n in nodes[1:]),
              "drives 2-7 stay in operation enabled with statusword bit 12 clear")
        del emcy[:]

        # CST: disable operation on the others too, switch the mode, enable, torque on joint 7.
        for node in nodes:
            node.state = "SWITCHED ON"
            node.op_mode = "CYCLIC SYNCHRONOUS TORQUE"
        check(all(n.op_mode == "CYCLIC SYNCHRONOUS TORQUE" for n in nodes), "op_mode CST")
        on_cycle[0] = lambda k: None
        for node in nodes:
            node.rpdo[1]["Target torque"].raw = 0
            node.state = "OPERATION ENABLED"
        check(all(n.state == "OPERATION ENABLED" for n in nodes), "operation enabled in CST")
        q7 = position(nodes[6])
        started = cycles[0]

        # 0.3 N m on joint 7 (0x6076 = 500 mN m: 600 per mille), ramped over 50 cycles: above the
        # joint's breakaway torque (0.21 N m, configs/robots/panda.yaml), so it turns.
        def cst_cycle(k):
            nodes[6].rpdo[1]["Target torque"].raw = min(k - started, 50) * 12
        on_cycle[0] = cst_cycle
        wait_cycles(250)
        moved = position(nodes[6]) - q7
        check(moved > 1000, "CST: 0.3 N m turned joint 7 (%+d urad)" % moved)
        check(not emcy, "no EMCY during the CST motion: %s" % emcy)
    finally:
        stop.set()
        thread.join()
        network.disconnect()
    if failures:
        print("%d check(s) failed" % len(failures))
        sys.exit(1)


if __name__ == "__main__":
    main(*sys.argv[1:4])
