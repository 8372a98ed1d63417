#!/usr/bin/env python3
"""Gravity-compensated float of the emulated robot from Python, over LCM (docs/bridge.md).

The robot adds gravity compensation itself; this controller only damps the joints,
tau = -D dq, in torque mode, for --duration seconds of robot time. It does what
csp_lcm_float does, with the Python types lcm-gen writes at build time.

Needs python3 only: it uses LCM's own Python module where one is installed, else CSP's
pure-Python client bridge/python/csp_lcm.py (Debian 12 packages no LCM Python module):

    build/apps/csp serve --clock lockstep --wait &
    PYTHONPATH=build/bridge/python:bridge/python python3 bridge/examples/python_float.py --duration 5

Use the lockstep clock: each cycle waits for its command, so Python's speed does not
matter; on the real-time clock a command counts only if it arrives within the 1 ms cycle.
"""
import argparse
import sys
import time

try:
    import lcm   # LCM's own module, where installed
except ImportError:
    try:
        import csp_lcm as lcm   # CSP's stand-in with the same API (bridge/python)
    except ImportError:
        sys.exit("python_float: no LCM client: add bridge/python to PYTHONPATH (CSP's csp_lcm) or install LCM's Python module")
try:
    from csp import config_reply_t, config_request_t, robot_state_t, torque_command_t
except ImportError:
    sys.exit("python_float: no CSP message types: build them (cmake --build build --target csp_lcm_types) "
             "and add build/bridge/python to PYTHONPATH")


def utime():
    return int(time.time() * 1e6)


class Robot:
    """The newest state and the replies, received on the robot's channels."""

    def __init__(self, url, prefix, timeout):
        self.lc = lcm.LCM(url)
        self.prefix = prefix
        self.timeout = timeout
        self.state = None
        self.replies = {}
        self.lc.subscribe(prefix + "CSP_STATE", self._on_state)
        self.lc.subscribe(prefix + "CSP_CONFIG_REPLY", self._on_reply)

    def _on_state(self, channel, data):
        state = robot_state_t.decode(data)
        if self.state is None or state.message_id >= self.state.message_id:
            self.state = state

    def _on_reply(self, channel, data):
        reply = config_reply_t.decode(data)
        self.replies[reply.request_id] = reply

    def _handle_until(self, done, what):
        deadline = time.monotonic() + self.timeout
        while not done():
            left = deadline - time.monotonic()
            if left <= 0:
                sys.exit(f"python_float: no {what} for {self.timeout} s (is csp serve running?)")
            self.lc.handle_timeout(max(1, int(left * 1000)))

    def state_after(self, message_id):
        """The newest state newer than message_id (a slow controller answers the newest one)."""
        self._handle_until(lambda: self.state is not None and self.state.message_id > message_id,
                           f"robot state on {self.prefix}CSP_STATE")
        return self.state

    def start_torque_session(self):
        request = config_request_t()
        request.utime = utime()
        request.request_id = 1
        request.request = config_request_t.START_MOTION
        request.control_mode = config_request_t.CONTROL_TORQUE
        self.lc.publish(self.prefix + "CSP_CONFIG", request.encode())
        self._handle_until(lambda: request.request_id in self.replies, f"reply on {self.prefix}CSP_CONFIG_REPLY")
        reply = self.replies[request.request_id]
        if not reply.ok:
            sys.exit(f"python_float: start of the control session refused: {reply.error}")

    def send_torque(self, message_id, tau, finished):
        command = torque_command_t()
        command.utime = utime()
        command.message_id = message_id   # the state this command answers (the FCI's rule)
        command.tau_J = tau
        command.motion_finished = finished
        self.lc.publish(self.prefix + "CSP_COMMAND", command.encode())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lcm-url", default="udpm://239.255.76.67:7667?ttl=0")
    parser.add_argument("--prefix", default="", help="channel prefix of the robot")
    parser.add_argument("--duration", type=float, default=5.0, help="motion time [s]")
    parser.add_argument("--damping", type=float, default=2.0, help="joint damping D [N m s/rad]")
    parser.add_argument("--timeout", type=float, default=2.0, help="wait for a state or a reply [s]")
    args = parser.parse_args()

    try:
        robot = Robot(args.lcm_url, args.prefix, args.timeout)
    except (OSError, RuntimeError, ValueError) as error:   # csp_lcm's OSError / ValueError, lcm's RuntimeError
        sys.exit(f"python_float: cannot open LCM at {args.lcm_url}: {error}")
    robot.state_after(-1)
    robot.start_torque_session()
    state = robot.state   # the first command answers the newest state
    start_ms = state.time
    commands = 0
    while True:
        finished = (state.time - start_ms) * 1e-3 >= args.duration - 1e-9
        robot.send_torque(state.message_id, [-args.damping * v for v in state.dq], finished)
        commands += 1
        state = robot.state_after(state.message_id)
        if finished or state.robot_mode != robot_state_t.MODE_MOVE:
            break
    mode = {robot_state_t.MODE_IDLE: "Idle", robot_state_t.MODE_REFLEX: "Reflex"}.get(state.robot_mode, str(state.robot_mode))
    print(f"python_float: {commands} commands, ended at t = {state.time * 1e-3:.3f} s in {mode} (LCM client: {lcm.__name__})")
    return 1 if state.robot_mode == robot_state_t.MODE_REFLEX else 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit("python_float: interrupted")
