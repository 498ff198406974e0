#!/usr/bin/env python3
"""Medians of the dg-loadgen lines bench/tls.sh collected: plaintext against TLS per N (and
TLS / plain), then TLS handshakes per second (full and resumed) per number of parallel slots."""
import statistics
import sys
from collections import defaultdict

PERSISTENT = ["rps", "p50_us", "p99_us", "p999_us", "cpu_us_per_req", "loadgen_cpu_us_per_req",
              "jain", "errors"]
HANDSHAKE = ["hs_per_s", "hs_p50_us", "hs_p99_us", "cycle_p50_us", "cycle_p99_us",
             "cpu_us_per_hs", "loadgen_cpu_us_per_hs", "resumed", "handshakes", "errors"]

runs = defaultdict(list)  # (kind, side, n) -> [dict]
for line in open(sys.argv[1]):
    if not line.strip():
        continue
    kind, side, n, _round, *kv = line.split()
    runs[(kind, side, int(n))].append({k: float(v) for k, v in (x.split("=") for x in kv)})


def med(key, f):
    values = [r[f] for r in runs[key] if f in r]
    return statistics.median(values) if values else float("nan")


def fmt(f, v):
    if v != v:  # nan
        return "-"
    if f in ("rps", "hs_per_s", "handshakes"):
        return f"{v:,.0f}"
    if f == "jain":
        return f"{v:.3f}"
    if f in ("errors", "resumed"):
        return f"{v:.0f}"
    return f"{v:.1f}"


print()
print("| N | side | runs | " + " | ".join(PERSISTENT) + " |")
print("|---|---|---|" + "---|" * len(PERSISTENT))
for n in sorted({k[2] for k in runs if k[0] == "persistent"}):
    for side in ("plain", "tls"):
        key = ("persistent", side, n)
        print(f"| {n} | {side} | {len(runs[key])} | " +
              " | ".join(fmt(f, med(key, f)) for f in PERSISTENT) + " |")
    ratios = []
    for f in PERSISTENT:
        p, t = med(("persistent", "plain", n), f), med(("persistent", "tls", n), f)
        ratios.append("-" if f == "errors" or not p else f"{t / p:.2f}x")
    print(f"| {n} | **TLS / plain** | | " + " | ".join(ratios) + " |")

hs = sorted({(k[1], k[2]) for k in runs if k[0] == "handshake"}, key=lambda k: (k[1], k[0]))
if hs:
    print()
    print("| C | handshake | runs | " + " | ".join(HANDSHAKE) + " |")
    print("|---|---|---|" + "---|" * len(HANDSHAKE))
    for mode, c in hs:
        key = ("handshake", mode, c)
        print(f"| {c} | {mode} | {len(runs[key])} | " +
              " | ".join(fmt(f, med(key, f)) for f in HANDSHAKE) + " |")
