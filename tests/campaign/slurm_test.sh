#!/bin/sh
# campaign.slurm_job_array: the small campaign (small.yaml) as a Slurm job array on a one-node
# cluster this script starts (munge, slurmctld, slurmd on 127.0.0.1, Debian's slurm-wlm and munge;
# the recipe of docs/campaign.md), against the same campaign run locally: the same table. Then a
# lost slice resubmitted (only its cases run again), and an unreachable Slurm (one clear error).
# Fails, not skips, without slurm-wlm or munge. Runs as root (slurmd starts the tasks).
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

# Wait for every case of campaign folder $1 (csp campaign status exits 0 when all are done).
wait_for_campaign() {
  waited=0
  until "$CSP" campaign status "$1" > "$WORK/status.txt" 2>&1; do
    waited=$((waited + 1))
    [ $waited -le 300 ] || fail "the job array did not finish in 300 s: $(cat "$WORK/status.txt"); squeue: $(squeue 2>&1 | tr '\n' ' ')"
    sleep 1
  done
}
# results.csv without its last column, the wall time of each run (the one number not deterministic).
deterministic() { sed 's/,[^,]*$//' "$1/results.csv"; }

"$CSP" campaign "$CAMPAIGN" --out "$WORK/local" --jobs 2 > /dev/null || fail "the local campaign failed"
"$CSP" campaign "$CAMPAIGN" --out "$WORK/slurm" --slurm --partition local --time 00:10:00 --array-size 4 ||
  fail "the Slurm submission failed"
wait_for_campaign "$WORK/slurm"
"$CSP" campaign collect "$WORK/slurm" > /dev/null || fail "csp campaign collect failed"
deterministic "$WORK/local" > "$WORK/local.csv"
deterministic "$WORK/slurm" > "$WORK/slurm.csv"
cmp "$WORK/local.csv" "$WORK/slurm.csv" || fail "the job array's table differs from the local run's"
[ "$(wc -l < "$WORK/slurm/runs.log")" = 24 ] || fail "runs.log: expected 24 case runs, got $(wc -l < "$WORK/slurm/runs.log")"

# A task that died with three of its cases: the resubmission runs those three only.
rm "$WORK/slurm/runs/c0001.json" "$WORK/slurm/runs/c0005.json" "$WORK/slurm/runs/c0009.json"
"$CSP" campaign status "$WORK/slurm" | grep -q '21 of 24 cases done' || fail "status after a lost slice: $("$CSP" campaign status "$WORK/slurm")"
"$CSP" campaign "$CAMPAIGN" --out "$WORK/slurm" --slurm --partition local --array-size 4 > /dev/null ||
  fail "the resubmission failed"
wait_for_campaign "$WORK/slurm"
"$CSP" campaign collect "$WORK/slurm" > /dev/null
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
echo "campaign.slurm_job_array: the job array's table equals the local run's (24 cases), a lost slice rerun alone, an unreachable Slurm reported"
