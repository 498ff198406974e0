#!/usr/bin/env python3
"""Medians per side and N of the dg-loadgen lines run.sh collected, and drivegate / baseline."""
import statistics
import sys
from collections import defaultdict

FIGURES = ["rps", "p50_us", "p99_us", "p999_us", "cpu_us_per_req", "jain", "errors"]

runs = defaultdict(list)  # (tag, side, n) -> [dict]
for line in open(sys.argv[1]):
    if line.startswith("#"):
        print(line.rstrip())
        continue
    tag, side, n, _round, *kv = line.split()
    runs[(tag, side, int(n))].append({k: float(v) for k, v in (x.split("=") for x in kv)})


def med(tag, side, n, f):
    values = [r[f] for r in runs[(tag, side, n)]]
    return statistics.median(values) if values else float("nan")


def fmt(f, v):
    if f == "rps":
        return f"{v:,.0f}"
    if f == "jain":
        return f"{v:.3f}"
    if f == "errors":
        return f"{v:.0f}"
    return f"{v:.1f}"


print()
print("| N | side | runs | " + " | ".join(FIGURES) + " |")
print("|---|---|---|" + "---|" * len(FIGURES))
for n in sorted({k[2] for k in runs if k[0] == "tcp"}):
    for side in ("baseline", "drivegate"):
        count = len(runs[("tcp", side, n)])
        print(f"| {n} | {side} | {count} | " +
              " | ".join(fmt(f, med("tcp", side, n, f)) for f in FIGURES) + " |")
    ratios = []
    for f in FIGURES:
        b, d = med("tcp", "baseline", n, f), med("tcp", "drivegate", n, f)
        ratios.append("-" if f == "errors" or b == 0 else f"{d / b:.2f}x")
    print(f"| {n} | **drivegate / baseline** | | " + " | ".join(ratios) + " |")
silent = sorted({k[2] for k in runs if k[0] == "silent"})
if silent:
    print()
    print("Independence (ed3100 silent on every poll, fdc1 streaming), drivegate medians:")
    print()
    print("| N | runs | " + " | ".join(FIGURES) + " |")
    print("|---|---|" + "---|" * len(FIGURES))
    for n in silent:
        count = len(runs[("silent", "drivegate", n)])
        print(f"| {n} | {count} | " +
              " | ".join(fmt(f, med("silent", "drivegate", n, f)) for f in FIGURES) + " |")
