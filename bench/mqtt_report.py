#!/usr/bin/env python3
"""bench/mqtt.sh's arithmetic. No dependencies.

mqtt_report.py latency PCAP SUB DEVICE METRIC
    PCAP: `drivegate capture` of the bus (docs/capture.md); SUB: `mosquitto_sub -F '%U %t %x'`
    lines (receive time, unix seconds with nanoseconds; topic; payload in hex). For each DDATA of
    DEVICE that carries METRIC, the frame it came from is the first drive -> gateway frame whose
    speed field (nidec-washer ACK: bytes 3..4, big-endian) holds that value, after the frame the
    DDATA before it was paired with and before the DDATA arrived. Latency = DDATA receive time -
    that frame's capture time. Prints one line of figures (and a cross-check: "the last frame
    received before each DDATA", which must agree when every poll changes the value).
mqtt_report.py load RESULTS
    RESULTS: the lines bench/mqtt.sh wrote per run; prints the table of runs and the ratios.

The Sparkplug payload is decoded here by hand from the protobuf wire format (Sparkplug B 3.0
Payload: timestamp 1, metrics 2, seq 3; Metric: name 1, alias 2, datatype 4, int_value 10,
long_value 11, float_value 12, double_value 13, boolean_value 14, string_value 15): nothing of
drivegate's code is involved.
"""
import statistics
import struct
import sys


def varint(b, i):
    r = s = 0
    while True:
        c = b[i]
        i += 1
        r |= (c & 0x7F) << s
        s += 7
        if c < 0x80:
            return r, i


def fields(b):
    i = 0
    while i < len(b):
        k, i = varint(b, i)
        f, t = k >> 3, k & 7
        if t == 0:
            v, i = varint(b, i)
        elif t == 1:
            v, i = b[i:i + 8], i + 8
        elif t == 5:
            v, i = b[i:i + 4], i + 4
        elif t == 2:
            n, i = varint(b, i)
            v, i = b[i:i + n], i + n
        else:
            raise ValueError(f"wire type {t}")
        yield f, v


def metric(b):
    m = {}
    for f, v in fields(b):
        if f == 1:
            m["name"] = v.decode()
        elif f == 2:
            m["alias"] = v
        elif f in (10, 11):
            m["value"] = v
        elif f == 12:
            m["value"] = struct.unpack("<f", v)[0]
        elif f == 13:
            m["value"] = struct.unpack("<d", v)[0]
        elif f == 14:
            m["value"] = bool(v)
        elif f == 15:
            m["value"] = v.decode(errors="replace")
    return m


def payload(b):
    return [metric(v) for f, v in fields(b) if f == 2]


def sparkplug_lines(path):
    """(receive time, message type, device, {name: value}) per line; names through the births."""
    aliases = {}
    out = []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) != 3:
                continue
            t, topic, hx = parts
            topic_parts = topic.split("/")
            kind = topic_parts[2]
            dev = topic_parts[4] if len(topic_parts) > 4 else ""
            metrics = payload(bytes.fromhex(hx))
            if kind in ("NBIRTH", "DBIRTH"):
                for m in metrics:
                    if "alias" in m and "name" in m:
                        aliases[(dev, m["alias"])] = m["name"]
            named = {}
            for m in metrics:
                name = m.get("name") or aliases.get((dev, m.get("alias")), f"alias{m.get('alias')}")
                named[name] = m.get("value")
            out.append((float(t), kind, dev, named))
    return out


def pcap_frames(path):
    """(time, direction, frame bytes) per packet of a drivegate capture."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 24 or data[:4] != b"\xd4\xc3\xb2\xa1":
        raise SystemExit(f"{path}: not a little-endian pcap ({len(data)} bytes)")
    i, out = 24, []
    while i + 16 <= len(data):
        sec, usec, incl, _ = struct.unpack("<IIII", data[i:i + 16])
        pkt = data[i + 16:i + 16 + incl]
        i += 16 + incl
        if len(pkt) < 6:
            continue
        a = pkt[4]
        d = pkt[5 + a]
        out.append((sec + usec / 1e6, pkt[1], pkt[6 + a + d:]))
    return out


def pct(xs, p):
    xs = sorted(xs)
    if not xs:
        return float("nan")
    k = (len(xs) - 1) * p / 100
    lo = int(k)
    hi = min(lo + 1, len(xs) - 1)
    return xs[lo] + (xs[hi] - xs[lo]) * (k - lo)


SPEED_MODES = {0x05, 0x09, 0x0B, 0x0C, 0x0D, 0x27, 0x29, 0x1B, 0x1D}  # ACKs with speed H L


def latency(pcap, sub, device, name):
    rx = []
    for t, direction, frame in pcap_frames(pcap):
        if direction != 1:
            continue
        speed = None
        if len(frame) == 7 and frame[0] == 0xA5 and frame[1] in SPEED_MODES:
            speed = (frame[3] << 8) | frame[4]
        rx.append((t, speed))
    msgs = [m for m in sparkplug_lines(sub) if m[1] == "DDATA" and m[2] == device]
    if not rx or not msgs:
        raise SystemExit(f"latency: {len(rx)} frames received, {len(msgs)} DDATA of {device}")
    # only the DDATA inside the capture (up to 100 ms after its last frame)
    msgs = [m for m in msgs if rx[0][0] < m[0] <= rx[-1][0] + 0.1]
    lat, last_lat, unmatched, j = [], [], 0, 0
    with_value = 0
    for t, _, _, named in msgs:
        if name not in named:
            continue  # a counter only, sent when its interval's timer fired
        # cross-check: the last frame received before the DDATA
        k = j
        while k < len(rx) and rx[k][0] < t:
            k += 1
        if k > 0:
            last_lat.append(t - rx[k - 1][0])
        with_value += 1
        v = named[name]
        v = v - (1 << 64) if isinstance(v, int) and v >= 1 << 63 else v
        m = j
        while m < len(rx) and rx[m][0] < t and rx[m][1] != v:
            m += 1
        if m < len(rx) and rx[m][0] < t:
            lat.append(t - rx[m][0])
            j = m + 1
        else:
            unmatched += 1
    polls = sum(1 for _, s in rx if s is not None)
    ms = [x * 1e3 for x in lat]
    lms = [x * 1e3 for x in last_lat]
    print(f"frames_rx={len(rx)} speed_acks={polls} ddata={len(msgs)} with_{name}={with_value} "
          f"matched={len(lat)} unmatched={unmatched} "
          f"p50_ms={pct(ms, 50):.3f} p90_ms={pct(ms, 90):.3f} p99_ms={pct(ms, 99):.3f} "
          f"max_ms={max(ms) if ms else float('nan'):.3f} mean_ms="
          f"{statistics.mean(ms) if ms else float('nan'):.3f} "
          f"xcheck_last_frame_p50_ms={pct(lms, 50):.3f} xcheck_p99_ms={pct(lms, 99):.3f}")


def load(path):
    runs = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            kv = dict(p.split("=", 1) for p in line.split())
            runs.append(kv)
    print("| run | side | load before (1 min) | drivegated CPU (s/s) | VmRSS MiB | VmHWM MiB | "
          "mosquitto CPU (s/s) | messages/s at the subscriber | good frames/s | "
          "other CPU on the machine (s/s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in runs:
        print(f"| {r['run']} | {r['side']} | {r['load']} | {float(r['dg_cpu']):.3f} | "
              f"{int(r['rss_kb']) / 1024:.1f} | {int(r['hwm_kb']) / 1024:.1f} | "
              f"{float(r['mosq_cpu']):.3f} | {float(r['msgs']):.0f} | {float(r['polls']):.0f} | "
              f"{float(r['other_cpu']):.2f} |")
    print()
    for key, label, scale in (("dg_cpu", "drivegated CPU (s/s)", 1), ("rss_kb", "VmRSS MiB", 1024),
                              ("hwm_kb", "VmHWM MiB", 1024), ("mosq_cpu", "mosquitto CPU (s/s)", 1),
                              ("msgs", "messages/s", 1), ("polls", "good frames/s", 1)):
        w = [float(r[key]) / scale for r in runs if r["side"] == "mqtt"]
        wo = [float(r[key]) / scale for r in runs if r["side"] == "no-mqtt"]
        if not w or not wo:
            continue
        mw, mwo = statistics.median(w), statistics.median(wo)
        ratio = f"{mw / mwo:.2f}x" if key in ("dg_cpu", "rss_kb", "hwm_kb", "polls") else "-"
        print(f"{label}: with [mqtt] median {mw:.3f} ({', '.join(f'{x:.3f}' for x in w)}); "
              f"without median {mwo:.3f} ({', '.join(f'{x:.3f}' for x in wo)}); ratio {ratio}; "
              f"difference {mw - mwo:+.3f}")


if __name__ == "__main__":
    if sys.argv[1] == "latency":
        latency(*sys.argv[2:6])
    elif sys.argv[1] == "load":
        load(sys.argv[2])
    else:
        raise SystemExit(__doc__)
