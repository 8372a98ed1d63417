# The vcan test, inside user-mode-linux (run_in_uml.sh): vcan0 and vcan1 are up. Every part runs
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

part "independent master (python-can): boot, SDO, 402, 1000 CST cycles vs the in-process emulator, RPDO silence, replay"
candump -L vcan0 > "$CSP_WORK/session.candump" &
dump=$!
sleep 0.3
$PY "$CSP_TESTS/master.py" session "$CSP_BIN" "$CSP_REFERENCE" "$CSP_WORK" || fail "session"
sleep 0.3
kill $dump

echo "=== $failed part(s) failed"
exit $failed
