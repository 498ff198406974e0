#!/usr/bin/env python3
"""serial_report.py ADAPTER WIRE_LOG WRITES_LOG TURNAROUND_US SIM_LINE FRAME_GAP_MS STREAMING

From a wire-timing simulator log (see cli/sim_host.h) and cmdlat.py's write log:
  poll cycles: maximal runs of request/reply transactions with no idle time over SPLIT_MS
  wire limit of a cycle: sum over its transactions of (request + reply bytes) x character time
    + one turnaround per reply; measured: first request byte read -> last reply byte written;
    efficiency = limit / measured. The adapter's inter-frame silence (its traits, FRAME_GAP_MS)
    is a protocol requirement, not gateway overhead: a second limit and efficiency add it
    between the transactions of a cycle, and the gap is also given above that silence.
  gateway gap: last reply byte written -> first byte of the next request read, inside a cycle
  command latency: write request sent -> first chunk on the line not seen in the second before
"""
import re
import statistics
import sys

SPLIT_MS = 20.0

adapter, wire_path, writes_path, turnaround_us, sim_line, frame_gap_ms, streaming = sys.argv[1:8]
frame_gap = int(frame_gap_ms) * 1_000_000
turnaround = int(turnaround_us) * 1000
m = re.search(r"wire timing (\d+) ns per character", sim_line)
char_ns = int(m.group(1)) if m else 0

events = []
for line in open(wire_path):
    p = line.split()
    if p[0] == "rx":
        events.append(("rx", int(p[1]), int(p[2]), int(p[3]), p[4] if len(p) > 4 else ""))
    elif p[0] == "tx":
        events.append(("tx", int(p[1]), int(p[2]), int(p[3]), ""))


def pct(v, q):
    if not v:
        return float("nan")
    v = sorted(v)
    return v[min(len(v) - 1, int(q * (len(v) - 1) + 0.5))]


# Transactions: an rx (possibly several chunks) answered by a tx.
cycles, gaps = [], []
cur = None  # [start_ns, end_ns, limit_ns, transactions]
last_tx_end = None
pending_rx_bytes = 0
first_rx = None
for kind, a, b, n, _ in events:
    if kind == "rx":
        if last_tx_end is not None and pending_rx_bytes == 0:
            idle = a - last_tx_end
            if idle <= SPLIT_MS * 1e6 and cur is not None:
                gaps.append(idle)
            elif cur is not None:
                cycles.append(cur)
                cur = None
        if pending_rx_bytes == 0:
            first_rx = a
        pending_rx_bytes += n
    else:  # tx: a reply (or an unsolicited frame when nothing was asked)
        if pending_rx_bytes == 0:
            continue
        if cur is None:
            cur = [first_rx, b, 0, 0]
        cur[1] = b
        cur[2] += (pending_rx_bytes + n) * char_ns + turnaround
        cur[3] += 1
        pending_rx_bytes = 0
        last_tx_end = b
if cur is not None:
    cycles.append(cur)
cycles = cycles[1:-1] if len(cycles) > 2 else cycles  # drop the cut-off ends
eff = [c[2] / (c[1] - c[0]) for c in cycles if c[1] > c[0]]
eff_gap = [(c[2] + (c[3] - 1) * frame_gap) / (c[1] - c[0]) for c in cycles if c[1] > c[0]]
lim_gap = [(c[2] + (c[3] - 1) * frame_gap) / 1e6 for c in cycles]
own = [g - frame_gap for g in gaps]
meas = [(c[1] - c[0]) / 1e6 for c in cycles]
lim = [c[2] / 1e6 for c in cycles]
tx_per = [c[3] for c in cycles]

# Command latency.
rx = [(a, h) for kind, a, _b, _n, h in events if kind == "rx"]
lat = []
for line in open(writes_path):
    _, t0, _t1, _rpm, ok = line.split()
    t0 = int(t0)
    if ok != "1":
        continue
    recent = {h for a, h in rx if t0 - 1_000_000_000 <= a < t0}
    for a, h in rx:
        if a >= t0 and h not in recent:
            if a - t0 < 1_000_000_000:
                lat.append((a - t0) / 1e3)
            break

med = lambda v: statistics.median(v) if v else float("nan")
if streaming == "1":  # unsolicited frames, no poll cycle: only the command latency means anything
    print(f"| {adapter} | {char_ns / 1000:.1f} | {int(frame_gap_ms)} | - | - | - | - | n/a | - | n/a "
          f"| - | - | {pct(lat, 0.5) / 1e3:.1f} / {pct(lat, 0.99) / 1e3:.1f} (n={len(lat)}) |")
    sys.exit(0)
print(f"| {adapter} | {char_ns / 1000:.1f} | {int(frame_gap_ms)} | {med(tx_per):.0f} | {len(cycles)} | "
      f"{med(meas):.2f} | {med(lim):.2f} | {med(eff):.3f} | {med(lim_gap):.2f} | {med(eff_gap):.3f} | "
      f"{med(gaps) / 1e3:.0f} / {pct(gaps, 0.99) / 1e3:.0f} | "
      f"{med(own) / 1e3:.0f} / {pct(own, 0.99) / 1e3:.0f} | "
      f"{pct(lat, 0.5) / 1e3:.1f} / {pct(lat, 0.99) / 1e3:.1f} (n={len(lat)}) |")
print(f"# {adapter}: char {char_ns / 1000:.1f} us, turnaround {int(turnaround_us)} us, "
      f"{len(cycles)} cycles of {statistics.median(tx_per) if tx_per else 0:.0f} transactions; "
      f"cycle measured median {statistics.median(meas) if meas else float('nan'):.2f} ms, "
      f"wire limit median {statistics.median(lim) if lim else float('nan'):.2f} ms, "
      f"efficiency median {statistics.median(eff) if eff else float('nan'):.3f} "
      f"(min {min(eff) if eff else float('nan'):.3f}); "
      f"gateway gap median {statistics.median(gaps) / 1e3 if gaps else float('nan'):.0f} us, "
      f"p99 {pct(gaps, 0.99) / 1e3:.0f} us (n={len(gaps)}); "
      f"command latency p50 {pct(lat, 0.5):.0f} us, p99 {pct(lat, 0.99):.0f} us (n={len(lat)})")
