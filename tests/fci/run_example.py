#!/usr/bin/env python3
"""Runs one of libfranka's own examples, unchanged, against `csp fci` over loopback, and checks it.

    run_example.py --csp CSP --scenario YAML --address 127.0.0.N [--clock realtime|lockstep]
                   [--realtime-kernel] [--stop-after S] [--time-limit S] -- EXAMPLE [ARGS...]

Starts `csp fci YAML --address 127.0.0.N`, waits for its line "listening on", runs EXAMPLE with the
robot's address as first argument (then ARGS) and a newline on stdin (the examples' "Press Enter"),
stops the server with SIGINT and checks both: the server ends with exit 0, the example the way
the check of its name (CHECKS below) expects. libfranka always connects to port 1337 (the gripper
to 1338), so each test has its own loopback address: the tests run in parallel.
Exit 0 when every check passes; otherwise 1, the last line ("FAILED: ...") saying what was wrong.
"""
import argparse
import json
import math
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import threading
import time

LISTEN_TIMEOUT_S = 10.0
STOP_TIMEOUT_S = 10.0


class CheckFailed(Exception):
    pass


def scenario_initial_q(path):
    """The scenario's start pose, `initial_q: [...]` (one line in every scenario; no YAML module in
    Python's standard library)."""
    with open(path, encoding="utf-8") as f:
        for line in f:
            match = re.match(r"\s*initial_q:\s*\[([^\]]*)\]", line)
            if match:
                return [float(x) for x in match.group(1).split(",")]
    raise CheckFailed(f"{path} has no `initial_q: [...]` line")


def libfranka_error(output):
    """The first libfranka exception message in the output (every one starts with "libfranka:"),
    or None. Needed because some examples end with exit 0 after an exception (the two impedance
    controllers catch it, print it and return 0)."""
    for line in output.splitlines():
        if "libfranka:" in line:
            return line.strip()
    return None


def check_echo_robot_state(output, initial_q):
    # echo_robot_state prints 101 robot states, one JSON object a line, then "Done.".
    states = []
    for line in output.splitlines():
        if line.startswith("{"):
            try:
                states.append(json.loads(line))
            except json.JSONDecodeError as error:
                raise CheckFailed(f"a robot state is not JSON ({error}): {line[:200]}")
    if len(states) != 101:
        raise CheckFailed(f"expected 101 robot states, got {len(states)}")
    if "Done." not in output:
        raise CheckFailed("echo_robot_state did not print 'Done.'")
    previous_time = -math.inf
    for i, state in enumerate(states):
        q = state["q"]
        worst = max(abs(a - b) for a, b in zip(q, initial_q))
        if len(q) != 7 or worst > 1e-3:
            raise CheckFailed(f"state {i}: q = {q} is not the scenario's initial_q {initial_q} "
                              "(within 1e-3 rad)")
        if state["robot_mode"] != "Idle":
            raise CheckFailed(f"state {i}: robot_mode is {state['robot_mode']!r}, expected 'Idle'")
        if state["current_errors"]:
            raise CheckFailed(f"state {i}: current_errors {state['current_errors']}")
        if state["time"] < previous_time:
            raise CheckFailed(f"state {i}: time {state['time']} ms goes back (previous {previous_time} ms)")
        previous_time = state["time"]


def check_communication_test(output, initial_q):
    # communication_test runs 10 s of zero torques and prints the average of the robot's
    # control_command_success_rate; libfranka warns below 0.95 ("MANY PACKETS GOT LOST").
    match = re.search(r"^Avg: ([0-9.]+)$", output, re.MULTILINE)
    if not match:
        raise CheckFailed("communication_test printed no 'Avg: <success rate>' line")
    average = float(match.group(1))
    if average < 0.95:
        raise CheckFailed(f"average control command success rate {average} < 0.95")


def check_finished_motion(output, initial_q):
    if "Finished motion, shutting down example" not in output:
        raise CheckFailed("the example did not print 'Finished motion, shutting down example'")


def check_reached_start_pose(output, initial_q):
    if "Finished moving to initial joint configuration." not in output:
        raise CheckFailed("the example did not print 'Finished moving to initial joint configuration.'")


def check_grasp(output, initial_q):
    if "Grasped object, will release it now." not in output:
        raise CheckFailed("grasp_object did not print 'Grasped object, will release it now.'")


def check_vacuum(output, initial_q):
    if "Vacuumed object, will release it now." not in output:
        raise CheckFailed("vacuum_object did not print 'Vacuumed object, will release it now.'")


def check_still_running(output, initial_q):
    # An endless controller: it must still be running (no exception) when the driver stops it.
    if "Press Enter to continue..." not in output:
        raise CheckFailed("the example did not reach its control loop ('Press Enter to continue...')")


CHECKS = {
    "echo_robot_state": check_echo_robot_state,
    "communication_test": check_communication_test,
    "generate_joint_position_motion": check_finished_motion,
    "generate_cartesian_pose_motion": check_finished_motion,
    "joint_impedance_control": check_reached_start_pose,
    "cartesian_impedance_control": check_still_running,
    "grasp_object": check_grasp,
    "vacuum_object": check_vacuum,
}


class Server:
    """`csp fci` in the background, its output collected line by line (a full pipe would block it)."""

    def __init__(self, command):
        self.lines = []
        self.listening = threading.Event()
        try:
            self.process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                            stderr=subprocess.STDOUT, text=True, errors="replace")
        except OSError as error:
            raise CheckFailed(f"cannot start csp fci: {error}")
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.process.stdout:
            self.lines.append(line)
            if "listening on" in line:
                self.listening.set()

    def output(self):
        return "".join(self.lines)

    def wait_for(self, text, timeout_s=10.0):
        """True once `text` is in csp fci's output: a line it writes after answering a client may
        come after the client has ended."""
        deadline = time.monotonic() + timeout_s
        while text not in self.output():
            if time.monotonic() > deadline:
                return False
            time.sleep(0.02)
        return True

    def wait_until_listening(self):
        deadline = time.monotonic() + LISTEN_TIMEOUT_S
        while not self.listening.wait(0.05):
            if self.process.poll() is not None:
                self.reader.join(1.0)
                raise CheckFailed(f"csp fci ended with exit code {self.process.returncode} before printing "
                                  "'listening on'")
            if time.monotonic() > deadline:
                raise CheckFailed(f"csp fci did not print 'listening on' within {LISTEN_TIMEOUT_S:g} s")

    def stop(self):
        """SIGINT, as a user's Ctrl-C; it must end with exit 0. Killed if it does not end."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
                self.reader.join(1.0)
                raise CheckFailed(f"csp fci did not end within {STOP_TIMEOUT_S:g} s of SIGINT (killed)")
        self.reader.join(1.0)
        if self.process.returncode != 0:
            raise CheckFailed(f"csp fci ended with exit code {self.process.returncode} on SIGINT, expected 0")


def example_command(example, address, arguments, realtime_kernel, fake_sys_kernel):
    command = [example, address] + arguments
    if not realtime_kernel:
        return command
    # libfranka's default RealtimeConfig::kEnforce refuses to run a control loop unless
    # /sys/kernel/realtime reads 1 (a PREEMPT_RT kernel); SCHED_FIFO itself works for root. The
    # example runs unchanged in a private mount namespace whose /sys/kernel holds only that file
    # (needs root; the mount is invisible outside). docs/fci-client-builds.md.
    with open(os.path.join(fake_sys_kernel, "realtime"), "w", encoding="ascii") as f:
        f.write("1\n")
    return ["unshare", "--mount", "sh", "-c", 'mount --bind "$0" /sys/kernel && exec "$@"',
            fake_sys_kernel] + command


def run_example(name, command, stop_after, time_limit):
    """Runs the example with "\\n" on stdin, prints its output, returns (exit code, output). With
    stop_after, the example is endless: SIGINT after that many seconds, and it must still have been
    running then."""
    try:
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, errors="replace")
    except OSError as error:
        raise CheckFailed(f"cannot start {name}: {error}")
    limit = stop_after if stop_after is not None else time_limit
    try:
        output, _ = process.communicate("\n", timeout=limit)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)
        try:
            output, _ = process.communicate(timeout=STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            process.kill()
            output, _ = process.communicate()
        print(output, end="", flush=True)
        if stop_after is None:
            raise CheckFailed(f"{name} did not end within {time_limit:g} s (stopped with SIGINT)")
        return process.returncode, output
    print(output, end="", flush=True)
    if stop_after is not None:
        raise CheckFailed(f"{name} ended (exit code {process.returncode}) before the driver stopped "
                          f"it after {stop_after:g} s")
    return process.returncode, output


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--csp", required=True, help="the csp executable")
    parser.add_argument("--scenario", required=True, help="the scenario YAML csp fci emulates")
    parser.add_argument("--address", required=True, help="this test's own loopback address, 127.0.0.N")
    parser.add_argument("--clock", choices=["realtime", "lockstep"],
                        help="csp fci --clock (default: the scenario's)")
    parser.add_argument("--realtime-kernel", action="store_true",
                        help="show the example a /sys/kernel/realtime of 1 (kEnforce; needs root)")
    parser.add_argument("--stop-after", type=float, help="endless example: SIGINT after this many seconds")
    parser.add_argument("--time-limit", type=float, default=120.0,
                        help="seconds the example may take (default 120)")
    parser.add_argument("example", help="the example's executable")
    parser.add_argument("arguments", nargs="*", help="its arguments after the robot's address")
    options = parser.parse_args()

    name = os.path.basename(options.example)
    check = CHECKS.get(name)
    if check is None:
        print(f"run_example.py: no check for `{name}` (known: {', '.join(CHECKS)})", file=sys.stderr)
        return 2
    server_command = [options.csp, "fci", options.scenario, "--address", options.address]
    if options.clock:
        server_command += ["--clock", options.clock]

    def run(server):
        initial_q = scenario_initial_q(options.scenario)
        with tempfile.TemporaryDirectory(prefix="csp_fci_sys_kernel_") as fake_sys_kernel:
            command = example_command(options.example, options.address, options.arguments,
                                      options.realtime_kernel, fake_sys_kernel)
            print("$ " + shlex.join(command), flush=True)
            started = time.monotonic()
            code, output = run_example(name, command, options.stop_after, options.time_limit)
            wall_seconds = time.monotonic() - started
            server.stop()
        # For the record (no check: a timed assertion would fail on a loaded machine): the robot
        # time the example's motions took (csp fci's count of motion cycles, 1 ms each) and the
        # example's wall time, which on the lockstep clock may be the shorter.
        motion_cycles = re.search(r"motion cycles (\d+)", server.output())
        if motion_cycles:
            print(f"{name}: motions {int(motion_cycles.group(1)) / 1000:.3f} s robot time, "
                  f"example {wall_seconds:.3f} s wall time", flush=True)
        error = libfranka_error(output)
        if error:
            raise CheckFailed(f"{name} reported an error: {error}")
        expected_code = -signal.SIGINT if options.stop_after is not None else 0
        if code != expected_code:
            raise CheckFailed(f"{name} ended with exit code {code}, expected {expected_code}")
        check(output, initial_q)

    return against_server(server_command, run, name, options.address)


def against_server(server_command, run, what, address):
    """Starts csp fci, and once it listens runs `run(server)` (which stops it, or raises
    CheckFailed); prints both programs' output and one PASSED or FAILED line. Returns the exit
    status, 0 or 1. Also run_client.py's."""
    server = None
    failure = None
    try:
        print("$ " + shlex.join(server_command), flush=True)
        server = Server(server_command)
        server.wait_until_listening()
        run(server)
    except CheckFailed as error:
        failure = error
    finally:
        if server is not None:
            if server.process.poll() is None:
                server.process.kill()
                server.process.wait()
            server.reader.join(1.0)
            print(f"--- csp fci's output:\n{server.output()}", end="", flush=True)
    if failure:
        print(f"FAILED: {failure}", flush=True)
        return 1
    print(f"PASSED: {what} against csp fci at {address}")
    return 0

if __name__ == "__main__":
    sys.exit(main())
