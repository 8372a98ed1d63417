#!/bin/sh
# The campaign's overhead per run: runs a second of `csp campaign` (forked workers, one JSON per
# case, the table and report) against a plain shell loop of `csp emulate` processes, both on the
# same cores and the same scenario (the default, 10 s, lockstep).
#   bench/bench_campaign.sh build/apps/csp [RUNS] [JOBS]
# With SLURM_CONF set to a running cluster (tests/campaign/one_node_slurm.sh start DIR makes one), also
# the same campaign as a Slurm job array of JOBS tasks, from submission to the collected table.
set -eu
CSP=$(realpath "$1")
RUNS=${2:-16}
JOBS=${3:-2}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cat > "$WORK/campaign.yaml" << YAML
base: default
runs: $RUNS
axes:
  - {parameter: faults.loss_probability, values: [0.0]}
YAML
now() { date +%s.%N; }
rate() { echo "$1 $2 $3" | awk '{ printf "%.2f runs/s (%.3f s per run)", $1 / ($3 - $2), ($3 - $2) / $1 }'; }

start=$(now)
i=0
while [ $i -lt "$RUNS" ]; do   # JOBS emulate processes at a time, as the campaign's workers
  j=0
  while [ $j -lt "$JOBS" ] && [ $i -lt "$RUNS" ]; do
    "$CSP" emulate default --seed $((i + 1)) > /dev/null 2>&1 &
    i=$((i + 1))
    j=$((j + 1))
  done
  wait
done
end=$(now)
echo "csp emulate loop, $JOBS at a time: $(rate "$RUNS" "$start" "$end")"

start=$(now)
"$CSP" campaign "$WORK/campaign.yaml" --out "$WORK/local" --jobs "$JOBS" > /dev/null 2>&1
end=$(now)
echo "csp campaign --jobs $JOBS:        $(rate "$RUNS" "$start" "$end")"

if [ -n "${SLURM_CONF:-}" ]; then
  start=$(now)
  "$CSP" campaign "$WORK/campaign.yaml" --out "$WORK/slurm" --slurm --array-size "$JOBS" > /dev/null
  # The array's finishing job writes the table: its line "... N of N cases done".
  until grep -qs "^csp campaign finish: .*: \([0-9]*\) of \1 cases done$" "$WORK/slurm"/slurm/finish_*.out; do sleep 0.2; done
  end=$(now)
  echo "csp campaign --slurm, $JOBS tasks: $(rate "$RUNS" "$start" "$end") (submission to the finishing job's table)"
fi
