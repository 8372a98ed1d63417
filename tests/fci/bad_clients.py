#!/usr/bin/env python3
"""Clients that break the FCI protocol, over real sockets, against one `csp fci`: the server must
survive each, still serve a well-behaved libfranka client after it, and end with exit 0 on SIGINT.

    bad_clients.py --csp CSP --scenario YAML --address 127.0.0.N --client FCI_REFLEX_RECOVERY --echo ECHO_ROBOT_STATE

The messages are built here with `struct` from the FCI wire layout (docs/fci.md; the robot's
protocol version is read from csp fci's "FCI version N" line). The well-behaved client is
tests/fci/clients' fci_reflex_recovery in `recover` mode (libfranka: readOnce,
automaticErrorRecovery, a short motion); a second client at once is libfranka's echo_robot_state.
The robot runs on the lockstep clock with a short --lockstep-timeout, so that this Python client
answers in time and a vanished client's missing commands take a known robot time.
Exit 0 when every check passes; otherwise 1, the last line ("FAILED: ...") saying what was wrong.
"""
import argparse
import json
import random
import re
import shlex
import socket
import struct
import subprocess
import sys
import time

from run_example import CheckFailed, Server

LOCKSTEP_TIMEOUT_S = 0.1
REPLY_TIMEOUT_S = 5.0
RECONNECT_S = 1.0

HEADER = struct.Struct("<III")                  # command, command_id, size (the whole message)
CONNECT = struct.Struct("<HH")                  # version, udp_port
CONNECT_RESPONSE = struct.Struct("<BH")         # status, the robot's version
MOVE = struct.Struct("<II6d")                   # controller mode, motion generator mode, 2 deviations
# The UDP robot state, up to q_d: message_id, 6 poses, m_ee, I_ee, F_x_Cee, m_load, I_load,
# F_x_Cload, elbow, elbow_d, tau_J, tau_J_d, dtau_J, q, q_d.
STATE_PREFIX = struct.Struct("<Q" + "16d" * 6 + "d9d3dd9d3d2d2d" + "7d" * 5)
# The whole state: then dq, dq_d, ddq_d, joint_contact, cartesian_contact, joint_collision,
# cartesian_collision, tau_ext_hat_filtered, O_F_ext_hat_K, K_F_ext_hat_K, O_dP_EE_d, O_ddP_O, elbow_c,
# delbow_c, ddelbow_c, O_T_EE_c, O_dP_EE_c, O_ddP_EE_c, theta, dtheta, the two mode codes, errors,
# reflex_reason, robot_mode, control_command_success_rate.
STATE_SIZE = STATE_PREFIX.size + struct.calcsize("<" + "7d" * 4 + "6d7d6d7d6d6d6d3d2d2d2d16d6d6d7d7d" + "BB41s41sBd")
Q_OFFSET = 1 + 96 + 1 + 9 + 3 + 1 + 9 + 3 + 2 + 2 + 21   # index of q[0] in STATE_PREFIX's values
# The motion generator and torque command: message_id, q_c, dq_c, O_T_EE_c, O_dP_EE_c, elbow_c,
# valid_elbow, motion_generation_finished, tau_J_d (version 7 adds torque_command_finished).
COMMAND_V5 = struct.Struct("<Q7d7d16d6d2dBB7d")
COMMAND_V7 = struct.Struct("<Q7d7d16d6d2dBB7dB")

MOVE_CODE, STOP_MOVE_CODE = 1, 2
MOVE_SUCCESS, MOVE_MOTION_STARTED = 0, 1
CONNECT_SUCCESS, CONNECT_INCOMPATIBLE = 0, 1


def check(condition, what):
    if not condition:
        raise CheckFailed(what)


def connect_when_listening(address):
    """A TCP connection to the command port. The robot listens again only once it has seen its
    previous client leave (it listens only while no client is connected): a connection right after
    another client ended may be refused for a moment, so it is tried again for up to RECONNECT_S."""
    deadline = time.monotonic() + RECONNECT_S
    while True:
        try:
            return socket.create_connection((address, 1337), timeout=REPLY_TIMEOUT_S)
        except ConnectionRefusedError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.01)


class Client:
    """One TCP connection to the command port and the UDP socket its Connect names."""

    def __init__(self, address):
        self.address = address
        self.tcp = connect_when_listening(address)
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.bind(("0.0.0.0", 0))
        self.udp.settimeout(REPLY_TIMEOUT_S)
        self.robot_udp = None
        self.next_id = 1
        self.version = None   # set by connect

    def send(self, command, payload=b"", size=None):
        message = HEADER.pack(command, self.next_id, HEADER.size + len(payload) if size is None else size) + payload
        self.next_id += 1
        self.tcp.sendall(message)

    def receive(self, size):
        data = b""
        while len(data) < size:
            chunk = self.tcp.recv(size - len(data))
            check(chunk, f"the robot closed the connection after {len(data)} of {size} bytes")
            data += chunk
        return data

    def response(self, fields):
        header = HEADER.unpack(self.receive(HEADER.size))
        check(header[2] == HEADER.size + fields.size, f"response of {header[2]} bytes, expected {HEADER.size + fields.size}")
        return header, fields.unpack(self.receive(fields.size))

    def connect(self, version):
        self.version = version
        self.send(0, CONNECT.pack(version, self.udp.getsockname()[1]))
        return self.response(CONNECT_RESPONSE)[1]

    def closed_by_robot(self):
        """True if the robot closes the connection within REPLY_TIMEOUT_S (after any bytes it sends)."""
        try:
            while self.tcp.recv(4096):
                pass
            return True
        except ConnectionResetError:
            return True
        except socket.timeout:
            return False

    def state(self, newer_than=-1):
        """The next robot state with a message_id above `newer_than` (the lockstep robot repeats
        its state while it waits): (message_id, q_d, size of the packet)."""
        while True:
            data, self.robot_udp = self.udp.recvfrom(4096)
            values = STATE_PREFIX.unpack_from(data)
            if values[0] > newer_than:
                return values[0], list(values[Q_OFFSET + 7:Q_OFFSET + 14]), len(data)

    def drop_received_states(self):
        self.udp.setblocking(False)
        try:
            while True:
                self.udp.recv(4096)
        except BlockingIOError:
            pass
        self.udp.settimeout(REPLY_TIMEOUT_S)

    def hold(self, message_id, q, cycles, finish=False):
        """Answers the next `cycles` states after `message_id` with q (the last one finishing the
        motion if `finish`); returns the last state's message_id."""
        for cycle in range(cycles):
            message_id = self.state(message_id)[0]
            self.udp.sendto(command_packet(self.version, message_id, q, finish and cycle == cycles - 1), self.robot_udp)
        return message_id

    def close(self):
        self.tcp.close()
        self.udp.close()


def command_packet(version, message_id, q_c, finished=False):
    fields = [message_id] + list(q_c) + [0.0] * (7 + 16 + 6 + 2) + [0, int(finished)] + [0.0] * 7
    return COMMAND_V5.pack(*fields) if version == 5 else COMMAND_V7.pack(*fields, 0)


def start_motion(client):
    """Move: a joint position motion under joint impedance; returns the motion's first state (the
    idle states received before are dropped)."""
    client.send(MOVE_CODE, MOVE.pack(0, 0, *[0.0] * 6))
    status = client.response(struct.Struct("<B"))[1][0]
    check(status == MOVE_MOTION_STARTED, f"Move answered status {status}, expected MotionStarted")
    client.drop_received_states()
    return client.state()


class Test:
    def __init__(self, options):
        self.options = options
        self.server = None
        self.version = None
        self.failures = []

    def diagnostics(self):
        return self.server.output()

    def wait_for_diagnostic(self, pattern, what):
        deadline = time.monotonic() + 10.0
        while not re.search(pattern, self.diagnostics()):
            check(time.monotonic() < deadline, f"csp fci did not report {what} (no line matching {pattern!r})")
            time.sleep(0.02)

    def count(self, pattern):
        return len(re.findall(pattern, self.diagnostics(), re.MULTILINE))

    def wait_for_count(self, pattern, count, what):
        deadline = time.monotonic() + 10.0
        while self.count(pattern) < count:
            check(time.monotonic() < deadline, f"csp fci did not report {what} (no new line matching {pattern!r})")
            time.sleep(0.02)

    def wait_until_no_client(self):
        """Until csp fci has seen every client leave: it listens again right after (a libfranka
        client started earlier could find the port closed: "Connection to FCI refused")."""
        self.wait_for_count(r"^csp fci: client \S+ (disconnected|lost)", self.count(r"^csp fci: client connected"),
                            "every client's leaving")
        time.sleep(0.01)

    def well_behaved_client(self):
        """libfranka connects, recovers and moves: the robot is still serving. Returns its first state."""
        check(self.server.process.poll() is None, f"csp fci ended (exit code {self.server.process.returncode})")
        command = [self.options.client, self.options.address, "recover"]
        print("$ " + shlex.join(command), flush=True)
        self.wait_until_no_client()
        result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60)
        print(result.stdout, end="", flush=True)
        lines = [json.loads(line) for line in result.stdout.splitlines() if line.startswith("{")]
        check(result.returncode == 0 and {"second_motion": "finished"} in lines,
              f"the well-behaved client failed (exit code {result.returncode})")
        return next(line["state"] for line in lines if "state" in line)

    def refused_with(self, client, diagnostic, what):
        check(client.closed_by_robot(), f"{what}: the robot did not close the connection")
        client.close()
        self.wait_for_diagnostic(diagnostic, what)

    # --- the bad clients ---------------------------------------------------------------------

    def garbage(self):
        client = Client(self.options.address)
        client.tcp.sendall(bytes(random.Random(1).randrange(1, 256) for _ in range(64)))
        self.refused_with(client, r"protocol error, connection closed: the first message must be Connect", "garbage")

    def connect_of_wrong_size(self):
        client = Client(self.options.address)
        client.send(0, CONNECT.pack(self.version, 1) + b"\0" * 4)
        self.refused_with(client, r"protocol error, connection closed: Connect of 20 bytes", "a Connect of 20 bytes")

    def move_before_connect(self):
        client = Client(self.options.address)
        client.send(MOVE_CODE, MOVE.pack(0, 0, *[0.0] * 6))
        self.refused_with(client, r"the first message must be Connect \(command 0\), not command 1", "a Move before Connect")

    def unknown_command(self):
        client = Client(self.options.address)
        check(client.connect(self.version)[0] == CONNECT_SUCCESS, "Connect refused")
        client.send(99)
        self.refused_with(client, r"command 99 is not a request of FCI version", "command 99")

    def stop_move_of_wrong_size(self):
        client = Client(self.options.address)
        check(client.connect(self.version)[0] == CONNECT_SUCCESS, "Connect refused")
        client.send(STOP_MOVE_CODE, b"\0" * 28)
        self.refused_with(client, r"StopMove of 40 bytes \(expected 12\)", "a StopMove of 40 bytes")

    def wrong_version(self):
        client = Client(self.options.address)
        status, robot_version = client.connect(3)
        check(status == CONNECT_INCOMPATIBLE and robot_version == self.version,
              f"Connect of version 3 answered status {status}, version {robot_version}; expected "
              f"IncompatibleLibraryVersion ({CONNECT_INCOMPATIBLE}) and {self.version}")
        self.refused_with(client, r"client of FCI version 3 refused", "a client of version 3")

    def cut_off_message(self):
        client = Client(self.options.address)
        client.tcp.sendall(HEADER.pack(0, 1, 16)[:7])
        left = self.count(r"client \S+ disconnected$")
        client.close()
        self.wait_for_count(r"client \S+ disconnected$", left + 1, "a client that left mid-message")

    def bad_udp_packets(self):
        client = Client(self.options.address)
        check(client.connect(self.version)[0] == CONNECT_SUCCESS, "Connect refused")
        message_id, q_start, state_size = start_motion(client)
        expected_size = (COMMAND_V5 if self.version == 5 else COMMAND_V7).size
        client.udp.sendto(b"\0" * 100, client.robot_udp)                              # the wrong size
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as stranger:             # another sender
            stranger.sendto(command_packet(self.version, message_id, q_start), client.robot_udp)
        # Answered, the robot steps to the next state: then the answer to the old one again.
        client.udp.sendto(command_packet(self.version, message_id, q_start), client.robot_udp)
        newer = client.state(message_id)[0]
        client.udp.sendto(command_packet(self.version, message_id, q_start), client.robot_udp)
        self.wait_for_diagnostic(rf"UDP command packet dropped: 100 bytes, expected {expected_size}", "a packet of 100 bytes")
        self.wait_for_diagnostic(rf"UDP command packet dropped: it answers state {message_id}, the current state is {newer}",
                                 "a packet answering an old state")
        check(state_size == STATE_SIZE, f"a robot state of {state_size} bytes, expected {STATE_SIZE}")
        print(f"state packets of {state_size} bytes; old state {message_id} answered at state {newer}", flush=True)
        # Then the client behaves: holds still for 50 cycles, finishes, and the motion succeeds.
        client.hold(message_id, q_start, 50, finish=True)
        status = client.response(struct.Struct("<B"))[1][0]
        check(status == MOVE_SUCCESS, f"the motion after the bad packets ended with status {status}, expected Success")
        client.close()

    def second_client(self):
        first = Client(self.options.address)
        check(first.connect(self.version)[0] == CONNECT_SUCCESS, "Connect refused")
        started = time.monotonic()
        try:
            socket.create_connection((self.options.address, 1337), timeout=REPLY_TIMEOUT_S).close()
            raise CheckFailed("a second client connected while one is connected")
        except ConnectionRefusedError:
            pass
        print(f"second connection refused after {time.monotonic() - started:.4f} s", flush=True)
        command = [self.options.echo, self.options.address]
        print("$ " + shlex.join(command), flush=True)
        result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=30)
        print(result.stdout, end="", flush=True)
        check("libfranka: Connection to FCI refused" in result.stdout and result.returncode != 0,
              "echo_robot_state as a second client was not refused")
        left = self.count(r"client \S+ disconnected$")
        first.close()
        self.wait_for_count(r"client \S+ disconnected$", left + 1, "the first client's leaving")

    def vanished_in_motion(self):
        client = Client(self.options.address)
        check(client.connect(self.version)[0] == CONNECT_SUCCESS, "Connect refused")
        message_id, q_start, _ = start_motion(client)
        client.udp.sendto(command_packet(self.version, message_id, q_start), client.robot_udp)
        client.hold(message_id, q_start, 30)
        client.close()
        self.wait_for_diagnostic(r"the client left during a motion", "the client lost in a motion")
        self.wait_for_diagnostic(r"motion ended in a reflex: .*communication_constraints_violation",
                                 "the reflex after the client's commands stopped")
        state = self.well_behaved_client()
        check(state["robot_mode"] == "Reflex", f"the next client saw robot_mode {state['robot_mode']!r}, expected 'Reflex'")
        # Checked at the end, after the remaining checks have run (a wrong flag is no reason to skip them).
        if "communication_constraints_violation" not in state["last_motion_errors"]:
            self.failures.append(f"after the vanished client, libfranka's state shows last_motion_errors "
                                 f"{state['last_motion_errors']}, expected communication_constraints_violation "
                                 "(which csp fci's diagnostics name; docs/fci-client-builds.md, \"Failing now\")")

    def run(self):
        command = [self.options.csp, "fci", self.options.scenario, "--address", self.options.address,
                   "--clock", "lockstep", "--lockstep-timeout", str(LOCKSTEP_TIMEOUT_S)]
        print("$ " + shlex.join(command), flush=True)
        self.server = Server(command)
        self.server.wait_until_listening()
        self.version = int(re.search(r"FCI version (\d+)", self.diagnostics()).group(1))
        cases = [self.garbage, self.connect_of_wrong_size, self.move_before_connect, self.unknown_command,
                 self.stop_move_of_wrong_size, self.wrong_version, self.cut_off_message, self.bad_udp_packets,
                 self.second_client, self.vanished_in_motion]
        for case in cases:
            print(f"--- {case.__name__}", flush=True)
            case()
            if case != self.vanished_in_motion:   # it runs the well-behaved client itself
                state = self.well_behaved_client()
                check(state["robot_mode"] == "Idle", f"after {case.__name__} the robot is in {state['robot_mode']!r}, expected 'Idle'")
        self.server.stop()
        report = self.diagnostics()
        for pattern, what in [(r"protocol errors (\d+)", 5), (r"refused versions (\d+)", 1),
                              (r"rejected command packets (\d+)", 1), (r"stale (\d+)", 1),
                              (r"foreign packets (\d+)", 1), (r"clients lost in a motion (\d+)", 1)]:
            match = re.search(pattern, report)
            check(match and int(match.group(1)) == what,
                  f"csp fci's report: {match.group(0) if match else 'no ' + pattern}, expected {what}")
        check(not self.failures, "; ".join(self.failures))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--csp", required=True)
    parser.add_argument("--scenario", required=True)
    parser.add_argument("--address", required=True)
    parser.add_argument("--client", required=True, help="tests/fci/clients' fci_reflex_recovery of this version")
    parser.add_argument("--echo", required=True, help="libfranka's echo_robot_state of this version")
    test = Test(parser.parse_args())
    failure = None
    try:
        test.run()
    except (CheckFailed, OSError, subprocess.TimeoutExpired) as error:
        failure = error
    finally:
        if test.server is not None:
            if test.server.process.poll() is None:
                test.server.process.kill()
                test.server.process.wait()
            test.server.reader.join(1.0)
            print(f"--- csp fci's output:\n{test.server.output()}", end="", flush=True)
    if failure:
        print(f"FAILED: {type(failure).__name__}: {failure}", flush=True)
        return 1
    print("PASSED: every bad client refused, csp fci serving after each")
    return 0


if __name__ == "__main__":
    sys.exit(main())
