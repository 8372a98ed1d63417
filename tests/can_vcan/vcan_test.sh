# The vcan test, inside user-mode-linux (run_in_uml.sh): vcan0 to vcan3 are up. Every part runs
# even if an earlier one failed; the exit code counts the failed parts. Environment: CSP_BIN
# (csp), CSP_REFERENCE (csp_can_reference), CSP_TESTS (this folder), CSP_VENDOR (shared/vendor),
# CSP_WORK (scratch folder on the host's disk).
failed=0
part() { echo "=== $1"; }
fail() { echo "FAIL  $1"; failed=$((failed + 1)); }
PY=/usr/bin/python3
for tool in candump canplayer canbusload cangen; do
  command -v $tool >/dev/null || { echo "FAIL  $tool not found: apt-get install can-utils"; exit 1; }
done
$PY -c "import can" || { echo "FAIL  python3-can missing: apt-get install python3-can"; exit 1; }

M="$CSP_TESTS/master.py"
W="$CSP_WORK"

part "independent master (python-can): boot, SDO, 402, 1000 CST cycles vs the in-process emulator, RPDO silence, replay"
candump -L vcan0 > "$W/session.candump" &
dump=$!
canbusload vcan0@1000000 > "$W/busload.txt" &
load=$!
sleep 0.5
$PY "$M" session "$CSP_BIN" "$CSP_REFERENCE" "$W" || fail "session"
sleep 2   # canbusload prints once a second: let it print the last traffic
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
kill $dump
$PY "$M" replay-compare "$W" || fail "replay"

part "bad input on the live bus: wrong DLC, unknown COB-IDs, SDO errors, out-of-range target, 1e5 frames"
$PY "$M" badinput "$CSP_BIN" "$W" || fail "bad input"

part "interop: the unmodified python-canopen (BaseNode402) maps PDOs by SDO, enables, moves in CSP and CST"
$PY "$CSP_TESTS/canopen_interop.py" "$CSP_BIN" "$CSP_VENDOR" "$W" || fail "python-canopen"

part "--split 4: the joints over vcan0..vcan3, each bus with its own nodes, its load under 100 %"
candump -L any > "$W/split.candump" &
dump=$!
sleep 0.3
"$CSP_BIN" can serve --iface vcan0 --split 4 --sync-producer --duration 0.3 > "$W/split.out" 2>&1 &
serve=$!
for i in $(seq 600); do grep -q "vcan3 707#00" "$W/split.candump" && break; sleep 0.1; done
for i in 0 1 2 3; do cansend vcan$i 000#0100; done
wait $serve || fail "split: csp can serve"
sleep 0.3
kill $dump
cat "$W/split.out"
$PY "$M" split "$W" || fail "split"

part "examples: csp_can_joint_impedance (csp::can::Master) and can_joint_impedance.py (python-can)"
for example in "$CSP_CAN_EXAMPLE --timeout 10" "$PY $CSP_EXAMPLES/can_joint_impedance.py --timeout 10"; do
  "$CSP_BIN" can serve --iface vcan0 --duration 1000 > "$W/example.out" 2>&1 &
  serve=$!
  sleep 2
  $example --iface vcan0 --cycles 300 || fail "$example"
  kill -INT $serve; wait $serve
  cat "$W/example.out"
  grep -q "motions 1, motion cycles 30[0-9], lost commands 0" "$W/example.out" || fail "$example: one motion of 300 cycles, none lost"
done

echo "=== $failed part(s) failed"
exit $failed
