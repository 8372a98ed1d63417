# csp-can-sandbox's bad input: each case names what was wrong and exits 125, before anything boots.
#   sh sandbox_errors.sh SANDBOX CSP
sandbox=$1 csp=$2
work=$(mktemp -d) || exit 1
failed=0
check() {  # EXPECTED-MESSAGE SANDBOX-ARGUMENT...
  expected=$1
  shift
  output=$("$sandbox" --work "$work" "$@" 2>&1)
  status=$?
  if [ "$status" = 125 ] && printf '%s' "$output" | grep -qF -- "$expected"; then
    echo "ok    $*"
  else
    echo "FAIL  $* -> exit $status, expected 125 and \"$expected\"; it said: $output"
    failed=$((failed + 1))
  fi
}
check "--kernel /nonexistent/vmlinuz-9.9: not a readable kernel image" --csp "$csp" --kernel /nonexistent/vmlinuz-9.9 -- true
check "--timeout: expected a whole number of seconds, got 'soon'" --csp "$csp" --timeout soon -- true
printf 'not a program\n' > "$work/notes.txt" && chmod 644 "$work/notes.txt"
check "--csp $work/notes.txt: not an executable file" --csp "$work/notes.txt" -- true
check "no command after --" --csp "$csp" --
rm -rf "$work"
exit $failed
