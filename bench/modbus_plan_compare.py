#!/usr/bin/env python3
"""Joins dg-modbus-plan tables (bench/modbus_plan.sh) run by several builds into one.

usage: modbus_plan_compare.py LABEL=TABLE_FILE...

Per profile and baud: the best plan the device allows (computed, from the first table that has
the row) and each run's measured planned cycle, in ms and as a multiple of that best plan.
"""
import sys


def rows(path):
    out = {}
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 10 or not cells[2].isdigit():
            continue
        key = (cells[0], int(cells[2]))
        out.setdefault(key, {})[cells[3]] = (int(cells[4]), float(cells[8]))
    return out


def main():
    runs = []
    for arg in sys.argv[1:]:
        label, path = arg.split("=", 1)
        runs.append((label, rows(path)))
    keys = []
    for _, r in runs:
        keys += [k for k in r if k not in keys]
    head = "| profile | baud | best plan: requests / ms |"
    head += "".join(f" {label}: ms / best |" for label, _ in runs)
    print(head)
    print("|---|---|---|" + "---|" * len(runs))
    for key in keys:
        best = next((r[key]["best plan (computed)"] for _, r in runs if key in r), None)
        if best is None:
            continue
        line = f"| {key[0]} | {key[1]} | {best[0]} / {best[1]:.2f} |"
        for _, r in runs:
            planned = r.get(key, {}).get("**planned**")
            line += f" {planned[1]:.2f} / {planned[1] / best[1]:.3f}x |" if planned else " n/a |"
        print(line)


if __name__ == "__main__":
    main()
