#!/usr/bin/env python3
"""Turns bench_stages' Google Benchmark JSON (--benchmark_out=FILE --benchmark_out_format=json) into
the Markdown table of docs/speed.md: one row per stage, our CPU time beside the peer's and their
ratio. With --benchmark_repetitions the medians are used (the `_median` aggregates), otherwise the
single runs. Names are <stage>/<who>, "ours" or the peer's function (bench/bench_stages.cpp).

Usage: benchmark_table.py stages.json [--time real|cpu]   (default cpu)
"""
import argparse
import json
import sys

UNITS = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


def milliseconds(entry, key):
    return entry[key] * UNITS[entry.get("time_unit", "ns")]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("json")
    parser.add_argument("--time", choices=("real", "cpu"), default="cpu")
    args = parser.parse_args()
    with open(args.json) as f:
        report = json.load(f)
    key = args.time + "_time"
    entries = report["benchmarks"]
    medians = [e for e in entries if e.get("aggregate_name") == "median"]
    chosen = medians if medians else [e for e in entries if e.get("run_type", "iteration") == "iteration"]

    stages = {}  # stage -> {"ours": ms, "peer": (name, ms)}, in the order of the run
    for e in chosen:
        name = e.get("run_name", e["name"])
        stage, _, who = name.partition("/")
        row = stages.setdefault(stage, {})
        if who == "ours":
            row["ours"] = milliseconds(e, key)
        else:
            row["peer"] = (who, milliseconds(e, key))

    context = report.get("context", {})
    reps = "median of %d repetitions" % medians[0]["repetitions"] if medians else "one run"
    print("%s time per call, ms (%s; %d x %.0f MHz, load %s)" % (
        args.time.upper() if args.time == "cpu" else "Wall", reps, context.get("num_cpus", 0),
        context.get("mhz_per_cpu", 0), " ".join("%.1f" % x for x in context.get("load_avg", []))))
    print()
    print("| stage | affine_orb | peer | peer's stage | affine_orb / peer |")
    print("|---|---:|---:|---|---:|")
    for stage, row in stages.items():
        ours = row.get("ours")
        peer_name, peer = row.get("peer", ("", None))
        ratio = "%.2f" % (ours / peer) if ours is not None and peer else ""
        print("| %s | %s | %s | %s | %s |" % (
            stage, "%.3f" % ours if ours is not None else "", "%.3f" % peer if peer is not None else "",
            peer_name, ratio))
    return 0


if __name__ == "__main__":
    sys.exit(main())
