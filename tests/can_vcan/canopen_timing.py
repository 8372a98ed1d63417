#!/usr/bin/python3
"""How long python-canopen (shared/vendor) waits for `csp can serve` where it runs: the figures
behind the timeouts docs/can.md gives for the sandbox's guest. Not a test (it asserts nothing and is
not in CTest): a measurement, re-run with

  bridge/can/tools/csp-can-sandbox --csp build/apps/csp -- /usr/bin/python3 tests/can_vcan/canopen_timing.py build/apps/csp ../shared/vendor

It prints p50 / p99 / max of: SDO answers with no SYNC; SDO answers while lockstep cycles run
(SYNC, wait for the last TPDO, repeat); the lockstep cycle; then, with python-can's periodic SYNC
every 10, 5 and 2 ms, the TPDO interval and SDO answers (at 2 ms python-canopen's receive thread
falls behind: the SDO answer comes after the 60 s limit, and the run ends there).
"""
import os
import sys
import tempfile
import threading
import time


def stats(name, seconds):
    s = sorted(seconds)
    print("%-46s n=%4d  p50 %7.1f ms  p99 %7.1f ms  max %7.1f ms" %
          (name, len(s), 1e3 * s[len(s) // 2], 1e3 * s[int(len(s) * 0.99)], 1e3 * s[-1]), flush=True)


def main(csp, vendor):
    sys.path.insert(0, os.path.join(vendor, "python-canopen"))
    import canopen

    network = canopen.Network()
    network.connect(channel="vcan0", interface="socketcan")
    nodes = []
    with tempfile.TemporaryDirectory() as folder:
        for n in range(1, 8):
            eds = os.path.join(folder, "joint%d.eds" % n)
            os.system("%s can eds --node %d -o %s" % (csp, n, eds))
            node = canopen.BaseNode402(n, eds)
            node.sdo.RESPONSE_TIMEOUT = 60.0   # long enough to see the real waits
            network.add_node(node)
            nodes.append(node)

    def sdo_answers(rounds):
        waits = []
        for _ in range(rounds):
            for node in nodes:
                begin = time.monotonic()
                node.sdo[0x6064].raw
                waits.append(time.monotonic() - begin)
        return waits

    stats("SDO answer, no SYNC", sdo_answers(40))
    for node in nodes:
        node.tpdo.read()
    network.nmt.state = "OPERATIONAL"
    time.sleep(0.5)

    stop = threading.Event()
    cycles = []

    def lockstep():
        last = nodes[6].tpdo[2]   # the last TPDO the drives send after a SYNC
        while not stop.is_set():
            begin, answered = time.monotonic(), last.timestamp
            network.sync.transmit()
            while last.timestamp == answered and not stop.is_set():
                time.sleep(0.0005)
            cycles.append(time.monotonic() - begin)

    thread = threading.Thread(target=lockstep)
    thread.start()
    time.sleep(1)
    stats("SDO answer, lockstep cycles running", sdo_answers(20))
    stop.set()
    thread.join()
    stats("lockstep cycle: SYNC -> the last TPDO", cycles)

    for period in (0.01, 0.005, 0.002):
        network.sync.start(period)
        time.sleep(1)
        intervals, last = [], None
        for _ in range(200):
            arrived = nodes[6].tpdo[2].wait_for_reception(60)
            if last is not None:
                intervals.append(arrived - last)
            last = arrived
        stats("TPDO2 interval, SYNC every %g ms" % (period * 1e3), intervals)
        stats("SDO answer, SYNC every %g ms" % (period * 1e3), sdo_answers(5))
        network.sync.stop()
        time.sleep(1)
    network.disconnect()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
