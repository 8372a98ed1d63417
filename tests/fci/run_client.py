#!/usr/bin/env python3
"""Runs one of CSP's own libfranka programs (tests/fci/clients) or an unchanged libfranka example
against `csp fci` over loopback, and checks what libfranka reports.

    run_client.py CHECK --csp CSP --scenario YAML --address 127.0.0.N [--clock C] -- PROGRAM [ARGS...]

CHECK:
  model         PROGRAM is fci_model_query: franka::Model (the library the robot serves) at a moving
                state must equal `csp model` of the scenario's robot file, internal inertia set and
                end effector at that state's q and dq, to 1e-9.
  reflex        PROGRAM is fci_reflex_recovery: its joint jump ends in franka::ControlException naming
                the reflex's error flag, the state then shows robot_mode Reflex with that flag in
                last_motion_errors; automaticErrorRecovery works and a second motion finishes.
  incompatible  PROGRAM is echo_robot_state of the other libfranka version: it must fail with
                libfranka's IncompatibleVersionException naming the robot's version.
The server is `csp fci YAML --address 127.0.0.N [--clock C]` (run_example.Server): it must end with
exit 0 on SIGINT. Exit 0 when every check passes; otherwise 1, the last line ("FAILED: ...") saying why.
"""
import argparse
import json
import os
import re
import shlex
import subprocess
import sys

from run_example import CheckFailed, Server, against_server

TOLERANCE = 1e-9
PROGRAM_TIME_LIMIT_S = 60.0


def run_program(command):
    print("$ " + shlex.join(command), flush=True)
    try:
        result = subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, errors="replace", timeout=PROGRAM_TIME_LIMIT_S)
    except subprocess.TimeoutExpired:
        raise CheckFailed(f"{os.path.basename(command[0])} did not end within {PROGRAM_TIME_LIMIT_S:g} s")
    print(result.stdout, end="", flush=True)
    return result.returncode, result.stdout


def json_lines(output):
    objects = []
    for line in output.splitlines():
        if line.startswith("{"):
            try:
                objects.append(json.loads(line))
            except json.JSONDecodeError as error:
                raise CheckFailed(f"not JSON ({error}): {line[:200]}")
    return objects


def scenario_field(path, pattern, what):
    """One value of the scenario file (no YAML module in Python's standard library): the first
    group of the first match of `pattern` (multi-line)."""
    with open(path, encoding="utf-8") as f:
        match = re.search(pattern, f.read(), re.MULTILINE)
    if not match:
        raise CheckFailed(f"{path}: no {what}")
    return match.group(1)


# ---------------------------------------------------------------------------------------------
# model

def csp_model(csp, scenario, q, dq, end_effector):
    robot = os.path.join(os.path.dirname(scenario), scenario_field(scenario, r"^robot:\s*(\S+)", "`robot:`"))
    # The robot's internal model (what the served library computes with): `robot_model: inertia:`.
    inertia = scenario_field(scenario, r"^robot_model:\s*\n\s+inertia:\s*(\S+)", "`robot_model: inertia:`")
    command = [csp, "model", "--robot", robot, "--inertia", inertia, "--ee", end_effector,
               "--q", ",".join(repr(x) for x in q), "--dq", ",".join(repr(x) for x in dq)]
    print("$ " + shlex.join(command), flush=True)
    result = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=30)
    if result.returncode != 0:
        raise CheckFailed(f"csp model failed (exit {result.returncode}): {result.stderr.strip()}")
    return json.loads(result.stdout)


def column_major_rotation(pose):
    """R of a 4x4 column-major pose, as rows."""
    return [[pose[c * 4 + r] for c in range(3)] for r in range(3)]


def body_jacobian(zero_jacobian, pose):
    """The Jacobian in the frame's own axes: [R^T v; R^T w] of the base-frame Jacobian (6x7,
    column-major), R the frame's orientation in the base frame."""
    rotation = column_major_rotation(pose)
    body = []
    for column in range(7):
        twist = zero_jacobian[column * 6:column * 6 + 6]
        for part in (twist[:3], twist[3:]):
            body += [sum(rotation[k][i] * part[k] for k in range(3)) for i in range(3)]
    return body


def compare(name, libfranka, reference, reference_name="csp model"):
    """None if they agree to TOLERANCE, else what differs."""
    if len(libfranka) != len(reference):
        return f"{name}: {len(libfranka)} values from libfranka, {len(reference)} from {reference_name}"
    worst = max(range(len(reference)), key=lambda i: abs(libfranka[i] - reference[i]))
    error = abs(libfranka[worst] - reference[worst])
    print(f"{name}: largest difference {error:.3g} (element {worst}: libfranka {libfranka[worst]!r}, "
          f"{reference_name} {reference[worst]!r})")
    if not error <= TOLERANCE:
        return f"{name} differs from {reference_name} by {error:.3g} > {TOLERANCE:g} (element {worst})"
    return None


def check_model(options, server):
    code, output = run_program([options.program, options.address] + options.arguments)
    results = json_lines(output)
    if code != 0 or len(results) != 1:
        raise CheckFailed(f"fci_model_query ended with exit code {code} and {len(results)} JSON results, "
                          "expected 0 and 1")
    got = results[0]
    if max(abs(v) for v in got["dq"]) < 0.1:
        raise CheckFailed(f"the sampled state is not moving (dq = {got['dq']}): Coriolis would be checked at rest")
    end_effector = scenario_field(options.scenario, r"^end_effector:\s*(\S+)", "`end_effector:`")
    with_end_effector = csp_model(options.csp, options.scenario, got["q"], got["dq"], end_effector)
    arm_alone = csp_model(options.csp, options.scenario, got["q"], got["dq"], "none")
    differences = [
        compare("mass", got["mass"], with_end_effector["mass"]),
        compare("coriolis", got["coriolis"], with_end_effector["coriolis"]),
        compare("gravity(state, {0, 0, -9.81})", got["gravity_earth"], with_end_effector["gravity"]),
        # libfranka's gravity(state) takes gravity_earth from the state's O_ddP_O, which the robot
        # reports as {0, 0, -9.81} (libfranka's robot_state.h: "hardcoded for now").
        compare("state's O_ddP_O", got["O_ddP_O"], [0.0, 0.0, -9.81], "libfranka's documented value"),
        compare("gravity(state)", got["gravity"], with_end_effector["gravity"]),
        compare("pose(kFlange)", got["pose_flange"], with_end_effector["O_T_F"]),
        compare("pose(kEndEffector)", got["pose_end_effector"], with_end_effector["O_T_EE"]),
        compare("zeroJacobian(kEndEffector)", got["zero_jacobian_end_effector"], with_end_effector["zero_jacobian"]),
        compare("bodyJacobian(kFlange)", got["body_jacobian_flange"],
                body_jacobian(arm_alone["zero_jacobian"], arm_alone["O_T_F"])),
    ]
    differences = [d for d in differences if d]
    if differences:
        raise CheckFailed("libfranka's franka::Model at csp fci: " + "; ".join(differences) +
                          " (docs/fci-client-builds.md, \"Failing now\")")


# ---------------------------------------------------------------------------------------------
# reflex

# The reflex a 0.1 rad step in one millisecond (100 rad/s) causes, as the robot names it.
JUMP_REFLEX = "joint_motion_generator_velocity_limits_violation"


def only_one(results, key):
    found = [r[key] for r in results if key in r]
    if len(found) != 1:
        raise CheckFailed(f"expected one {key!r} line, got {len(found)}")
    return found[0]


def check_reflex(options, server):
    code, output = run_program([options.program, options.address] + options.arguments)
    results = json_lines(output)
    errors = [r["error"] for r in results if "error" in r]
    if errors:
        raise CheckFailed(f"libfranka error outside the jump: {errors[0]}")
    before = only_one(results, "state")
    if before["robot_mode"] != "Idle" or before["current_errors"] or before["last_motion_errors"]:
        raise CheckFailed(f"the robot is not idle and error free at the start: {before['robot_mode']}, "
                          f"{before['current_errors']}, {before['last_motion_errors']}")
    exception = only_one(results, "exception")
    if exception is None:
        raise CheckFailed("the jump raised no franka::ControlException")
    if "reflex" not in exception or JUMP_REFLEX not in exception:
        raise CheckFailed(f"the ControlException does not name a reflex with {JUMP_REFLEX}: {exception!r}")
    after = only_one(results, "state_after_reflex")
    if after["robot_mode"] != "Reflex":
        raise CheckFailed(f"robot_mode after the reflex is {after['robot_mode']!r}, expected 'Reflex'")
    if JUMP_REFLEX not in after["last_motion_errors"]:
        raise CheckFailed(f"last_motion_errors after the reflex are {after['last_motion_errors']}, "
                          f"expected {JUMP_REFLEX}")
    for flag in after["last_motion_errors"]:
        if flag not in exception:
            raise CheckFailed(f"last_motion_errors has {flag}, which the exception does not name")
    only_one(results, "recovered")
    if only_one(results, "second_motion") != "finished" or code != 0:
        raise CheckFailed(f"the motion after automaticErrorRecovery did not finish (exit code {code})")
    if not server.wait_for("reflex"):
        raise CheckFailed("csp fci's diagnostics do not mention the reflex")


# ---------------------------------------------------------------------------------------------
# incompatible

def check_incompatible(options, server):
    code, output = run_program([options.program, options.address] + options.arguments)
    robot_version = int(re.search(r"FCI version (\d+)", server.output()).group(1))
    match = re.search(r"libfranka: Incompatible library version \(server version: (\d+), library version: (\d+)\)",
                      output)
    if not match:
        raise CheckFailed("the client did not report libfranka's IncompatibleVersionException")
    if int(match.group(1)) != robot_version or int(match.group(2)) == robot_version:
        raise CheckFailed(f"IncompatibleVersionException names server {match.group(1)}, library {match.group(2)}; "
                          f"the robot speaks {robot_version}")
    if code == 0:
        raise CheckFailed("the refused client ended with exit code 0")
    if not server.wait_for("refused"):
        raise CheckFailed("csp fci's diagnostics do not mention the refused client")


CHECKS = {"model": check_model, "reflex": check_reflex, "incompatible": check_incompatible}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("check", choices=sorted(CHECKS))
    parser.add_argument("--csp", required=True, help="the csp executable")
    parser.add_argument("--scenario", required=True, help="the scenario YAML csp fci emulates")
    parser.add_argument("--address", required=True, help="this test's own loopback address, 127.0.0.N")
    parser.add_argument("--clock", choices=["realtime", "lockstep"], help="csp fci --clock (default: its own)")
    parser.add_argument("program", help="the client program")
    parser.add_argument("arguments", nargs="*", help="its arguments after the robot's address")
    options = parser.parse_args()

    server_command = [options.csp, "fci", options.scenario, "--address", options.address]
    if options.clock:
        server_command += ["--clock", options.clock]
    def run(server):
        CHECKS[options.check](options, server)
        server.stop()

    return against_server(server_command, run, options.check, options.address)

if __name__ == "__main__":
    sys.exit(main())
