#!/usr/bin/env python3
"""cmdlat.py PORT SECONDS WRITE_MS OUT: starts unit 1 running, then every WRITE_MS writes a new
setpoint (holding register 1) and records, per write, CLOCK_MONOTONIC ns just before the request
leaves and when the reply came back. Setpoints step through 1500..3000 rpm so that each native
frame carrying one is new on the line."""
import socket
import struct
import sys
import time

from mbwrite import request

port, seconds, write_ms, out = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
with socket.create_connection(("127.0.0.1", port)) as s, open(out, "w") as log:
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    time.sleep(1.0)  # first polls
    request(s, 1, 1, struct.pack(">BHHBHH", 16, 0, 2, 4, 1, 1500))  # run_forward at 1500 rpm
    time.sleep(1.0)
    end = time.monotonic() + seconds
    i = 0
    while time.monotonic() < end:
        rpm = 1550 + (i % 30) * 50
        t0 = time.monotonic_ns()
        try:
            request(s, 2 + i % 1000, 1, struct.pack(">BHH", 6, 1, rpm))
            ok = 1
        except RuntimeError:
            ok = 0
        log.write(f"write {t0} {time.monotonic_ns()} {rpm} {ok}\n")
        i += 1
        time.sleep(write_ms / 1000.0)
