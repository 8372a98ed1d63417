#!/usr/bin/env python3
"""The Python side of tests/test_bridge_python.cpp: CSP's pure-Python LCM client (bridge/python/csp_lcm.py)
with the types lcm-gen writes (build/bridge/python), against peers using LCM's C library.

    python_lcm_peer.py publish URL CHANNEL FILE [CHANNEL FILE ...]
        publishes each file's bytes once on its channel, then exits.
    python_lcm_peer.py echo URL
        answers each message on a TEST_* channel on ECHO_<channel>: a robot_state_t on TEST_STATE is
        decoded and encoded again by the generated type, any other payload is sent back as received;
        exits 0 on TEST_STOP, 1 after 30 s without it.
"""
import sys
import time

import csp_lcm
from csp import robot_state_t


def publish(url, pairs):
    lc = csp_lcm.LCM(url)
    for channel, path in zip(pairs[0::2], pairs[1::2]):
        with open(path, "rb") as f:
            lc.publish(channel, f.read())
    return 0


def echo(url):
    lc = csp_lcm.LCM(url)
    stopped = []

    def answer(channel, data):
        if channel == "TEST_STOP":
            stopped.append(True)
            return
        if channel == "TEST_STATE":
            data = robot_state_t.decode(data).encode()
        lc.publish("ECHO_" + channel, data)

    lc.subscribe("TEST_.*", answer)   # a regex, matched against the whole channel name
    deadline = time.monotonic() + 30
    while not stopped and time.monotonic() < deadline:
        lc.handle_timeout(100)
    return 0 if stopped else 1


if __name__ == "__main__":
    if len(sys.argv) >= 5 and sys.argv[1] == "publish" and len(sys.argv) % 2 == 1:
        sys.exit(publish(sys.argv[2], sys.argv[3:]))
    if len(sys.argv) == 3 and sys.argv[1] == "echo":
        sys.exit(echo(sys.argv[2]))
    sys.exit(__doc__)
