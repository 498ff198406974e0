#!/usr/bin/env python3
"""http_summary.py RESULTS: medians of bench/http_load.sh's runs, per N and side, with / without,
and the scraper's figures (medians over the "with" runs)."""
import statistics
import sys
from collections import defaultdict

FIGURES = ["rps", "p50_us", "p99_us", "p999_us", "cpu_us_per_req", "errors"]
SCRAPE = ["requests", "errors", "late", "p50_ms", "p99_ms", "max_ms", "metrics_p50_ms",
          "status_p50_ms", "metrics_bytes", "status_bytes", "cpu_ms"]

runs = defaultdict(list)  # (side, n) -> [dict]
scrapes = []
for line in open(sys.argv[1]):
    if line.startswith("#"):
        print(line.rstrip())
        continue
    p = line.split()
    if not p:
        continue
    if p[0] == "scrape":
        kv = dict(x.split("=") for x in p[1:])
        side = kv.pop("side", "with")
        scrapes.append((side, {k: float(v) for k, v in kv.items()}))
        continue
    _tag, side, n, rnd, *kv = p
    d = {k: float(v) for k, v in (x.split("=") for x in kv)}
    d["round"] = int(rnd)
    runs[(side, int(n))].append(d)


def med(side, n, f):
    v = [r[f] for r in runs[(side, n)]]
    return statistics.median(v) if v else float("nan")


def fmt(f, v):
    if f == "rps":
        return f"{v:,.0f}"
    if f == "errors":
        return f"{v:.0f}"
    return f"{v:.1f}"


print()
print("| N | side | runs | " + " | ".join(FIGURES) + " |")
print("|---|---|---|" + "---|" * len(FIGURES))
SIDES = [s for s in ("without", "with", "decoy") if any(k[0] == s for k in runs)]
NAME = {"without": "without scraper", "with": "with scraper", "decoy": "decoy scraper (404s)"}
for n in sorted({k[1] for k in runs}):
    for side in SIDES:
        print(f"| {n} | {NAME[side]} | {len(runs[(side, n)])} | " +
              " | ".join(fmt(f, med(side, n, f)) for f in FIGURES) + " |")
    for num, den in (("with", "without"), ("decoy", "without"), ("with", "decoy")):
        if num not in SIDES or den not in SIDES:
            continue
        ratios = []
        for f in FIGURES:
            a, b = med(den, n, f), med(num, n, f)
            ratios.append("-" if f == "errors" or a == 0 else f"{b / a:.3f}x")
        print(f"| {n} | **{num} / {den}** | | " + " | ".join(ratios) + " |")
    # Per round (the two runs of a round are back to back): the spread of the paired ratio.
    pairs = []
    by_round = {r["round"]: r for r in runs[("without", n)]}
    for r in runs[("with", n)]:
        o = by_round.get(r["round"])
        if o and o["p99_us"] > 0 and o["rps"] > 0:
            pairs.append((r["p99_us"] / o["p99_us"], r["rps"] / o["rps"]))
    if pairs:
        print()
        print(f"N = {n}, per round with / without: p99 " +
              " ".join(f"{p:.3f}" for p, _ in pairs) + "; rps " +
              " ".join(f"{q:.3f}" for _, q in pairs))
if scrapes:
    print()
    print("Scraper (medians over the runs; latency = connect -> last body byte):")
    print()
    print("| side | runs | " + " | ".join(SCRAPE) + " |")
    print("|---|---|" + "---|" * len(SCRAPE))
    for side in ("with", "decoy"):
        sc = [s for k, s in scrapes if k == side]
        if not sc:
            continue
        print(f"| {side} | {len(sc)} | " + " | ".join(
            (f"{v:.2f}" if f.endswith("_ms") else f"{v:.0f}")
            for f in SCRAPE for v in [statistics.median(s[f] for s in sc)]) + " |")

    print()
    for side in ("with", "decoy"):
        sc = [s for k, s in scrapes if k == side]
        if sc:
            secs = statistics.median(s["seconds"] for s in sc)
            cpu = statistics.median(s["cpu_ms"] for s in sc)
            print(f"{side}: scraper CPU {cpu:.0f} ms over {secs:g} s = {cpu / secs / 10:.2f} % of "
                  "the load generator's CPU")
