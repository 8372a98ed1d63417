#!/usr/bin/python3
"""Markdown table of CSP against its peers from `csp_bench --benchmark_format=json` output.

    build/bench/csp_bench --benchmark_format=json > bench.json
    /usr/bin/python3 bench/ratio_table.py bench.json            # or: ... | ratio_table.py -

Benchmarks are paired by name, BM_<Quantity>_CSP with BM_<Quantity>_<Peer>, the peer KDL
(csp_bench) or Pinocchio (csp_pinocchio_bench); a column pair per peer in the runs (TWINS lists
the CSP quantities whose twin has another name). With --benchmark_repetitions, --stat picks the
median (default) or the minimum over the repetitions; the minimum is the steadier figure on a
machine shared with other work, e.g.

    csp_bench --benchmark_repetitions=10 --benchmark_min_time=0.05 \
              --benchmark_enable_random_interleaving=true --benchmark_format=json > bench.json
    ratio_table.py bench.json --stat min

Compiler and flags come from the JSON context that csp_bench records; --compiler and --flags
override them. Standard library only.
"""

import argparse
import json
import signal
import statistics
import sys

PEERS = ("KDL", "Pinocchio")
# Per peer: CSP quantity -> the peer's quantity it is compared with, where the names differ.
TWINS = {"KDL": {"ForwardDynamicsCholesky": "ForwardDynamics"}}
# Per peer: CSP quantities without a counterpart, and why.
NO_TWIN = {"KDL": {"CoriolisMatrix": "KDL has no Coriolis matrix (only C(q,dq) dq)"}}
# Targets for CSP on the project's 2-core reference machine [ns] (printed with --targets).
TARGETS_NS = {"Rnea": 250, "MassMatrix": 200, "ForwardDynamics": 500, "FkJacobian": 150}

TO_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("json", nargs="*", default=["-"],
                        help="csp_bench JSON output files ('-' for stdin); several runs are pooled")
    parser.add_argument("--time", choices=("cpu", "real"), default="cpu", help="cpu_time (default) or real_time")
    parser.add_argument("--stat", choices=("median", "min"), default="median",
                        help="statistic over repetitions: median (default) or min")
    parser.add_argument("--compiler", help="compiler to print instead of the JSON context's")
    parser.add_argument("--flags", help="flags to print instead of the JSON context's")
    parser.add_argument("--targets", action="store_true", help="add a column with the CSP targets")
    return parser.parse_args()


def load(paths):
    """The first file's context and the benchmarks of all files."""
    context, benchmarks = None, []
    for path in paths:
        if path == "-":
            data = json.load(sys.stdin)
        else:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        context = context if context is not None else data.get("context", {})
        benchmarks += data.get("benchmarks", [])
    return {"context": context or {}, "benchmarks": benchmarks}


def times_ns(benchmarks, key, stat):
    """Benchmark name -> time in ns over its repetitions (a single run is its own median and minimum)."""
    runs, medians = {}, {}
    for b in benchmarks:
        name = b.get("run_name", b["name"])
        ns = b[key] * TO_NS[b.get("time_unit", "ns")]
        if b.get("run_type") != "aggregate":
            runs.setdefault(name, []).append(ns)
        elif b.get("aggregate_name") == "median":
            medians[name] = ns   # only used with --benchmark_report_aggregates_only
    pick = min if stat == "min" else statistics.median
    times = {name: pick(values) for name, values in runs.items()}
    for name, ns in medians.items():
        times.setdefault(name, ns)
    return times


def split(name):
    """BM_<Quantity>_<CSP|Peer> -> (Quantity, side), or None."""
    if not name.startswith("BM_"):
        return None
    quantity, _, side = name[3:].rpartition("_")
    return (quantity, side) if (side == "CSP" or side in PEERS) and quantity else None


def fmt(ns):
    return f"{ns:.1f}" if ns < 100 else f"{ns:.0f}"


def main():
    args = parse_args()
    data = load(args.json)
    context = data.get("context", {})
    times = times_ns(data.get("benchmarks", []), "cpu_time" if args.time == "cpu" else "real_time", args.stat)
    runs_per_benchmark = {}
    for b in data["benchmarks"]:
        if b.get("run_type") != "aggregate":
            name = b.get("run_name", b["name"])
            runs_per_benchmark[name] = runs_per_benchmark.get(name, 0) + 1
    repetitions = max(runs_per_benchmark.values(), default=1)

    # Rows in registration order (family_index), whatever order the runs were interleaved in.
    family = {}
    for b in data.get("benchmarks", []):
        name = b.get("run_name", b["name"])
        family[name] = min(family.get(name, 1 << 30), b.get("family_index", len(family)))
    sides, order = {}, []   # side -> quantity -> ns
    for name in sorted(times, key=lambda n: family.get(n, 0)):
        parsed = split(name)
        if parsed is None:
            continue
        quantity, side = parsed
        sides.setdefault(side, {})[quantity] = times[name]
        if side == "CSP":
            order.append(quantity)
    csp = sides.get("CSP", {})
    peers = [peer for peer in PEERS if peer in sides]

    header = ["Quantity", "CSP [ns]"]
    for peer in peers:
        header += [f"{peer} [ns]", f"{peer}/CSP"]
    if args.targets:
        header.append("CSP target [ns]")
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|")
    notes = []
    for quantity in order:
        label, row = quantity, []
        for peer in peers:
            twin = TWINS.get(peer, {}).get(quantity, quantity)
            if twin != quantity:
                label += f" ({peer}: {twin})"
            if twin in sides[peer]:
                row += [fmt(sides[peer][twin]), f"{sides[peer][twin] / csp[quantity]:.2f}"]
            else:
                row += ["—", "—"]
                if quantity in NO_TWIN.get(peer, {}):
                    notes.append(f"{quantity}: {NO_TWIN[peer][quantity]}.")
        row = [label, fmt(csp[quantity])] + row
        if args.targets:
            target = TARGETS_NS.get(quantity)
            row.append("" if target is None else f"{target} ({'met' if csp[quantity] <= target else 'MISSED'})")
        print("| " + " | ".join(row) + " |")

    print()
    for note in notes:
        print(f"- {note}")
    compiler = args.compiler or context.get("csp_compiler", "unknown")
    flags = args.flags or context.get("csp_flags", "unknown")
    over = f", {args.stat} of {repetitions} runs" if repetitions > 1 else ""
    print(f"- {args.time} time per call{over}; compiler: {compiler}; CSP flags: `{' '.join(flags.split())}`"
          f" ({context.get('csp_build_type', 'build type unknown')})")
    if "KDL" in peers:
        print(f"- KDL {context.get('kdl_version', '?')} (distribution package); model: {context.get('csp_model', '?')}")
    if "Pinocchio" in peers:
        print(f"- Pinocchio {context.get('pinocchio_version', '?')} header-only, compiled in the bench (compiler"
              f" above, CSP's flags); model: {context.get('csp_model', '?')}")
        agreement = {key[len("agreement_"):]: value for key, value in context.items() if key.startswith("agreement_")}
        if agreement:
            worst = max(agreement, key=lambda quantity: float(agreement[quantity]))
            print(f"- CSP and Pinocchio agree on every quantity and state to {agreement[worst]} relative"
                  f" (largest: {worst})")
    mhz = context.get("mhz_per_cpu")
    print(f"- host: {context.get('host_name', '?')}, {context.get('num_cpus', '?')} CPUs"
          f"{f' at {mhz} MHz' if mhz else ''}, date {context.get('date', '?')}")


if __name__ == "__main__":
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)   # quiet when piped into head
    main()
