# The vcan test, inside the sandbox's guest kernel (`csp-can-sandbox --no-serve -- sh vcan_test.sh`): vcan0
# to vcan6 are up. Every part runs even if an earlier one failed; the exit code counts the failed
# parts. Environment: CSP_BIN (csp), CSP_REFERENCE (csp_can_reference), CSP_SANDBOX
# (csp-can-sandbox, run here with --here as a user runs it), CSP_CAN_EXAMPLE, CSP_EXAMPLES,
# CSP_TESTS (this folder), CSP_VENDOR (shared/vendor), CSP_WORK (scratch folder on the host's disk).
failed=0
start=$(date +%s)
part() { echo "=== [$(($(date +%s) - start)) s] $1"; }
fail() { echo "FAIL  $1"; failed=$((failed + 1)); }
PY=/usr/bin/python3
for tool in candump canplayer canbusload cangen; do
  command -v $tool >/dev/null || { echo "FAIL  $tool not found: apt-get install can-utils"; exit 1; }
done
$PY -c "import can" || { echo "FAIL  python3-can missing: apt-get install python3-can"; exit 1; }

M="$CSP_TESTS/master.py"
W="$CSP_WORK"
mkdir -p "$W" || exit 1
# The guest's emulated CPU has AVX2, not AVX-512: a build for a newer host's CPU stops here, named.
"$CSP_BIN" demo --samples 100 --out "$W/demo" > "$W/demo.out" 2>&1
case $? in
  0) ;;
  132) echo "FAIL  $CSP_BIN stops on an illegal instruction in the guest: build with -DCSP_NATIVE=OFF -DCMAKE_CXX_FLAGS=-march=x86-64-v3"; exit 1 ;;
  *) cat "$W/demo.out"; echo "FAIL  csp demo"; exit 1 ;;
esac
# Waits until a recorder (candump) writing to FILE has caught up: its size unchanged
# for a second (at most a minute). A slow guest schedules it late, and it must not be stopped with
# frames still queued in its socket.
settled() { last=-1; for i in $(seq 60); do size=$(wc -c < "$1"); [ "$size" = "$last" ] && return; last=$size; sleep 1; done; }
# A master as a user runs it: csp-can-sandbox starts `csp can serve`, runs the master, stops the
# server and returns the master's exit code; its files go to $W/$1.
sandbox() { name=$1; shift; "$CSP_SANDBOX" --here --csp "$CSP_BIN" --work "$W/$name" "$@"; }

part "independent master (python-can): boot, SDO, 402, 1000 CST cycles vs the in-process emulator, RPDO silence, replay"
candump -L vcan0 > "$W/session.candump" &
dump=$!
canbusload vcan0@1000000 > "$W/busload.txt" &
load=$!
sleep 0.5
$PY "$M" session "$CSP_BIN" "$CSP_REFERENCE" "$W" || fail "session"
sleep 2   # canbusload prints once a second: let it print the last traffic
settled "$W/session.candump"
kill $dump $load

part "canbusload vcan0@1000000 vs csp can serve's own figure"
$PY "$M" busload "$W" || fail "busload"

part "candump -L log -> canplayer -> the same TPDO stream"
$PY "$M" master-frames "$W" 100
candump -L vcan0 > "$W/replay.candump" &
dump=$!
sleep 0.3
"$CSP_BIN" can serve --iface vcan0 --duration 1000 > "$W/replay.out" 2>&1 &
serve=$!
for i in $(seq 600); do grep -q "707#00" "$W/replay.candump" && break; sleep 0.1; done
canplayer -I "$W/master.candump" || fail "canplayer"
sleep 1
kill -INT $serve; wait $serve
settled "$W/replay.candump"
kill $dump
$PY "$M" replay-compare "$W" || fail "replay"

part "bad input on the live bus: wrong DLC, unknown COB-IDs, SDO errors, restricted COB-IDs, out-of-range target, 1e5 frames, a flood into a stopped server"
$PY "$M" badinput "$CSP_BIN" "$W" || fail "bad input"

part "stateful fuzz: random NMT, SDO, COB-IDs, PDO remapping, 402 transitions, modes and cycles, invariants after each step"
$PY "$M" fuzz "$CSP_BIN" "$W" 400 || fail "fuzz"

part "csp-can-sandbox: candump as the master sees the drives' heartbeats; the master's exit code comes back"
sandbox candump -- sh -c 'candump -L -n 14 vcan0 > "$0" && exit 3' "$W/candump-master.out"
[ $? = 3 ] || fail "sandbox: candump failed, or the master's exit code 3 did not come back"
for n in 1 2 3 4 5 6 7; do
  grep -q " vcan0 70$n#7F\$" "$W/candump-master.out" || fail "sandbox: candump saw no pre-operational heartbeat 70$n#7F"
done

part "interop: the unmodified python-canopen (BaseNode402), started by csp-can-sandbox, reads the start pose, maps PDOs by SDO, enables, moves in CSP and CST"
sandbox interop -- $PY "$CSP_TESTS/canopen_interop.py" "$CSP_BIN" "$CSP_VENDOR" "$W" || fail "python-canopen"

part "--split 4: the joints over vcan0..vcan3, each bus with its own nodes, its load under 100 %"
candump -L any > "$W/split.candump" &
dump=$!
sleep 0.3
"$CSP_BIN" can serve --iface vcan0 --split 4 --sync-producer --duration 600 > "$W/split.out" 2>&1 &
serve=$!
for i in $(seq 600); do grep -q "vcan3 707#00" "$W/split.candump" && break; sleep 0.1; done
for i in 0 1 2 3; do cansend vcan$i 000#0100; done
# Stopped once node 7 has sent 200 TPDO1s, not after a fixed robot time: a slow guest may start
# the nodes only after a short run has ended.
for i in $(seq 600); do [ "$(grep -c "vcan3 187#" "$W/split.candump")" -ge 200 ] && break; sleep 0.1; done
kill -INT $serve
wait $serve || fail "split: csp can serve"
settled "$W/split.candump"
kill $dump
cat "$W/split.out"
$PY "$M" split "$W" || fail "split"

part "examples, with their default timeouts, started by csp-can-sandbox: csp_can_joint_impedance (csp::can::Master) and can_joint_impedance.py (python-can)"
for example in "$CSP_CAN_EXAMPLE" "$PY $CSP_EXAMPLES/can_joint_impedance.py"; do
  name=example-$(basename "${example##* }")
  sandbox "$name" -- $example --iface vcan0 --cycles 300 || fail "$example"
  grep -q "motions 1, motion cycles 30[0-9], lost commands 0" "$W/$name/serve.log" || fail "$example: one motion of 300 cycles, none lost"
done

echo "=== [$(($(date +%s) - start)) s] $failed part(s) failed"
exit $failed
