# Runs a command (the vcan test in its sandbox) and prints its outline first: the parts, their
# failures, Python's errors and the sandbox's own lines, then the whole output. CI shows a failed
# test's first lines, and a run of several minutes prints hundreds.
# Usage: failures_first.sh LOG COMMAND [ARGUMENT...]
log=$1
shift
mkdir -p "$(dirname "$log")" || exit 1
"$@" > "$log" 2>&1
rc=$?
echo "exit code $rc; the outline (the whole output follows, and is in $log):"
grep -E '^(===|FAIL|Traceback|[A-Za-z]*Error|csp-can-sandbox:)' "$log"
echo "--- the whole output ---"
cat "$log"
exit $rc
