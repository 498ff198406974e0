#!/usr/bin/env python3
"""scraper.py PORT RATE SECONDS OUT [--keep-alive] [--decoy]: an HTTP scraper for
bench/http_load.sh.

For SECONDS seconds, fetches /metrics and /api/v1/status of 127.0.0.1:PORT RATE times a second
each, interleaved: one request every 1 / (2 x RATE) s, on an absolute schedule (request i is due
at start + i x period, so a slow answer does not shift the ones after it; a request that is due
while the one before is still in flight starts as soon as that one ends and counts as "late").
Each request is GET over HTTP/1.1 on a new TCP connection (connect, send, read the whole body,
close), or with --keep-alive on one connection per path kept open; latency is connect (or send)
-> last body byte, CLOCK_MONOTONIC. --decoy: the same requests, connections and pacing, but to two paths the daemon does not serve
(404 "not found", 10 bytes): the client's and the connections' cost without rendering anything.
Writes one line to OUT:
  scrape requests=N errors=E late=L p50_ms= p99_ms= max_ms= metrics_bytes= status_bytes=
         cpu_ms= (this process's user + system CPU over the scraping)
"""
import http.client
import resource
import sys
import time

port, rate, seconds, out = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
keep_alive = "--keep-alive" in sys.argv[5:]
decoy = "--decoy" in sys.argv[5:]
paths = ["/metrics", "/api/v1/status"]
sent = {"/metrics": "/metrics-decoy", "/api/v1/status": "/api/v1/status-decoy"} if decoy else {}
want = 404 if decoy else 200
period = 1.0 / (2 * rate)
conns = {}
lat = {p: [] for p in paths}
size = {p: 0 for p in paths}
errors = late = 0


def fetch(path):
    c = conns.get(path) if keep_alive else None
    if c is None:
        c = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
        if keep_alive:
            conns[path] = c
    try:
        c.request("GET", sent.get(path, path), headers={} if keep_alive else {"Connection": "close"})
        r = c.getresponse()
        body = r.read()
        if r.status != want:
            raise RuntimeError(f"{path}: {r.status}")
        return len(body)
    except Exception:
        c.close()
        conns.pop(path, None)
        raise
    finally:
        if not keep_alive:
            c.close()


def usage():
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime


cpu0 = usage()
start = time.monotonic()
i = 0
while True:
    due = start + i * period
    if due - start >= seconds:
        break
    now = time.monotonic()
    if due > now:
        time.sleep(due - now)
    elif now - due > 0.002:
        late += 1
    path = paths[i % 2]
    t0 = time.monotonic_ns()
    try:
        size[path] = fetch(path)
        lat[path].append((time.monotonic_ns() - t0) / 1e6)
    except Exception as e:  # noqa: BLE001: counted and reported
        errors += 1
        print(f"scraper: {e}", file=sys.stderr)
    i += 1
cpu_ms = (usage() - cpu0) * 1e3


def pct(v, q):
    if not v:
        return float("nan")
    v = sorted(v)
    return v[min(len(v) - 1, int(q * (len(v) - 1) + 0.5))]


every = lat[paths[0]] + lat[paths[1]]
with open(out, "a") as f:
    f.write(f"scrape requests={len(every)} errors={errors} late={late} "
            f"p50_ms={pct(every, 0.5):.3f} p99_ms={pct(every, 0.99):.3f} "
            f"max_ms={max(every) if every else float('nan'):.3f} "
            f"metrics_p50_ms={pct(lat['/metrics'], 0.5):.3f} "
            f"status_p50_ms={pct(lat['/api/v1/status'], 0.5):.3f} "
            f"metrics_bytes={size['/metrics']} status_bytes={size['/api/v1/status']} "
            f"cpu_ms={cpu_ms:.0f} seconds={seconds:g}\n")
