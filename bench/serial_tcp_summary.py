#!/usr/bin/env python3
"""serial_tcp_summary.py RESULTS: bench/serial_tcp.sh's runs ("SIDE ROUND | row of
serial_report.py |"), the median per side over the rounds of each figure, and tcp / pty."""
import math
import statistics
import sys
from collections import defaultdict

# Columns of serial_report.py's row after the adapter: char us, frame gap ms, tx/cycle, cycles,
# cycle ms, limit ms, eff, limit+gap ms, eff+gap, gap p50 / p99, above p50 / p99, cmd p50 / p99.
runs = defaultdict(list)
for line in open(sys.argv[1]):
    side, _round, rest = line.split(None, 2)
    c = [x.strip() for x in rest.strip().strip("|").split("|")]

    def two(s):
        a, b = s.split("(")[0].split("/")
        return float(a), float(b)

    gap50, gap99 = two(c[10])
    own50, own99 = two(c[11])
    cmd50, cmd99 = two(c[12])
    runs[side].append({
        "cycles": float(c[4]), "cycle_ms": float(c[5]), "limit_ms": float(c[6]), "eff": float(c[7]),
        "limit_gap_ms": float(c[8]), "eff_gap": float(c[9]), "gap_p50_us": gap50,
        "gap_p99_us": gap99, "above_p50_us": own50, "above_p99_us": own99, "cmd_p50_ms": cmd50,
        "cmd_p99_ms": cmd99,
    })

FIG = ["cycle_ms", "limit_ms", "eff", "limit_gap_ms", "eff_gap", "gap_p50_us", "gap_p99_us",
       "above_p50_us", "above_p99_us", "cmd_p50_ms", "cmd_p99_ms"]


def med(side, f):
    v = [r[f] for r in runs[side] if not math.isnan(r[f])]
    return statistics.median(v) if v else float("nan")


def fmt(f, v):
    if f.startswith("eff"):
        return f"{v:.3f}"
    if f.endswith("_us"):
        return f"{v:.0f}"
    return f"{v:.2f}"


print()
print("Medians over the rounds (each round's figure is itself a median over its cycles):")
print()
print("| side | runs | cycles (sum) | " + " | ".join(FIG) + " |")
print("|---|---|---|" + "---|" * len(FIG))
for side in ("pty", "tcp"):
    print(f"| {side} | {len(runs[side])} | {sum(r['cycles'] for r in runs[side]):.0f} | " +
          " | ".join(fmt(f, med(side, f)) for f in FIG) + " |")
ratio = []
for f in FIG:
    a, b = med("pty", f), med("tcp", f)
    ratio.append(f"{b / a:.3f}x" if a and not math.isnan(a) and not math.isnan(b) else "-")
print("| **tcp / pty** | | | " + " | ".join(ratio) + " |")
for side in ("pty", "tcp"):
    e = [r["eff"] for r in runs[side]]
    g = [r["eff_gap"] for r in runs[side]]
    if e:
        print(f"\n{side}: eff per run {' '.join(f'{x:.3f}' for x in e)}; "
              f"eff+gap per run {' '.join(f'{x:.3f}' for x in g)}", end="")
print()
