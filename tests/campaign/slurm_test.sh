#!/bin/sh
# campaign.slurm_job_array: the small campaign (small.yaml) as a Slurm job array on a one-node
# cluster this script starts (munge, slurmctld, slurmd on 127.0.0.1, Debian's slurm-wlm and munge;
# the recipe of docs/campaign.md), against the same campaign run locally: the same table. One task of
# the array dies (cancelled): the finishing job submits its cases again by itself and writes the
# table. Then a lost slice resubmitted by hand (only its cases run again), and an unreachable Slurm
# (one clear error). Fails, not skips, without slurm-wlm or munge. Runs as root (slurmd starts the tasks).
#   slurm_test.sh CSP SOURCE_DIR WORK_DIR
set -eu
CSP=$1
SOURCE=$2
WORK=$3
CAMPAIGN=$SOURCE/tests/campaign/small.yaml
fail() { echo "campaign.slurm_job_array: FAIL: $*" >&2; exit 1; }

rm -rf "$WORK"
S=$WORK/slurm_state
# Stop what this script started, by PID, however it ends.
stop_daemons() { sh "$SOURCE/tests/campaign/one_node_slurm.sh" stop "$S"; }
trap stop_daemons EXIT
sh "$SOURCE/tests/campaign/one_node_slurm.sh" start "$S" || fail "the one-node Slurm did not start"
export SLURM_CONF=$S/slurm.conf

# Wait for campaign folder $1's finishing job to have written the table of all its cases (the last
# line of a finish_*.out: "... N of N cases done", then results.csv's line).
wait_for_table() {
  waited=0
  until [ -f "$1/results.csv" ] && grep -qs "^csp campaign finish: .*: \([0-9]*\) of \1 cases done$" "$1"/slurm/finish_*.out &&
    "$CSP" campaign status "$1" > "$WORK/status.txt" 2>&1; do
    waited=$((waited + 1))
    [ $waited -le 300 ] || fail "no table after 300 s: $("$CSP" campaign status "$1" 2>&1); squeue: $(squeue 2>&1 | tr '\n' ' ')"
    sleep 1
  done
}
# results.csv without its last three columns, the controller's time and the wall time of each run
# (the numbers that are not deterministic).
deterministic() { sed -E 's/(,[^,]*){3}$//' "$1/results.csv"; }

"$CSP" campaign "$CAMPAIGN" --out "$WORK/local" --jobs 2 > /dev/null || fail "the local campaign failed"

# The partition held down while task 1 is cancelled: a task that dies before its first case, for sure.
scontrol update PartitionName=local State=DOWN || fail "scontrol could not hold the partition"
"$CSP" campaign "$CAMPAIGN" --out "$WORK/slurm" --slurm --partition local --time 00:10:00 --array-size 4 ||
  fail "the Slurm submission failed"
array=$(sed -n '1s/^array \([0-9]*\) .*/\1/p' "$WORK/slurm/slurm/submissions.log")
[ -n "$array" ] || fail "submissions.log: expected the array's job id, got: $(cat "$WORK/slurm/slurm/submissions.log")"
scancel "${array}_1" || fail "scancel ${array}_1 failed"
scontrol update PartitionName=local State=UP
wait_for_table "$WORK/slurm"
[ "$(wc -l < "$WORK/slurm/slurm/submissions.log")" = 2 ] ||
  fail "expected the dead task's cases submitted again once: $(cat "$WORK/slurm/slurm/submissions.log")"
grep -qs "6 of 24 cases not done after the job array: submitted them again" "$WORK/slurm"/slurm/finish_*.out ||
  fail "the first finishing job did not submit the dead task's 6 cases again: $(cat "$WORK/slurm"/slurm/finish_*.out)"
deterministic "$WORK/local" > "$WORK/local.csv"
deterministic "$WORK/slurm" > "$WORK/slurm.csv"
cmp "$WORK/local.csv" "$WORK/slurm.csv" || fail "the job array's table differs from the local run's"
[ "$(wc -l < "$WORK/slurm/runs.log")" = 24 ] || fail "runs.log: expected 24 case runs, got $(wc -l < "$WORK/slurm/runs.log")"

# A task that died with three of its cases, submitted again by hand: those three run, only.
rm "$WORK/slurm/runs/c0001.json" "$WORK/slurm/runs/c0005.json" "$WORK/slurm/runs/c0009.json" "$WORK/slurm/results.csv"
rm "$WORK/slurm"/slurm/finish_*.out
"$CSP" campaign status "$WORK/slurm" | grep -q '21 of 24 cases done' || fail "status after a lost slice: $("$CSP" campaign status "$WORK/slurm")"
"$CSP" campaign "$CAMPAIGN" --out "$WORK/slurm" --slurm --partition local --array-size 4 > /dev/null ||
  fail "the resubmission failed"
wait_for_table "$WORK/slurm"
deterministic "$WORK/slurm" > "$WORK/slurm.csv"
cmp "$WORK/local.csv" "$WORK/slurm.csv" || fail "the resubmitted job array's table differs from the local run's"
[ "$(wc -l < "$WORK/slurm/runs.log")" = 27 ] || fail "runs.log: expected 24 + 3 case runs, got $(wc -l < "$WORK/slurm/runs.log")"

# No Slurm to talk to: one clear error, the folder's results kept.
stop_daemons
status=0
"$CSP" campaign "$CAMPAIGN" --out "$WORK/unreachable" --slurm > "$WORK/unreachable.txt" 2>&1 || status=$?
[ $status = 2 ] || fail "an unreachable Slurm: expected exit status 2, got $status"
grep -q 'sbatch could not submit the job array' "$WORK/unreachable.txt" ||
  fail "an unreachable Slurm: expected sbatch's error, got: $(cat "$WORK/unreachable.txt")"
echo "campaign.slurm_job_array: the job array's table equals the local run's (24 cases), a dead task's cases run again by the finishing job, a lost slice rerun alone, an unreachable Slurm reported"
