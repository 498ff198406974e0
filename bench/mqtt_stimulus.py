#!/usr/bin/env python3
"""bench/mqtt.sh's stimulus: values that keep changing on simulated ed3100 drives.

mqtt_stimulus.py PERIOD_MS ADDRESSES FIFO...
    Every PERIOD_MS, writes to each FIFO (the stdin of a `drivegate sim ed3100` with the given
    addresses, e.g. "1,2,3,4") one operator command per address: `@A monitor 0D01 V 388`, the
    output-current monitor (1 decimal, A, "normal" format bits: 388) set to a new value V each
    time. The gateway's polls then read a changed value, so every device has something to publish
    (a real drive's current is never still). Runs until killed. Only the simulators do work here;
    drivegated sees nothing but its own polls.
"""
import os
import sys
import time


def main():
    period = int(sys.argv[1]) / 1000.0
    addresses = [int(a) for a in sys.argv[2].split(",")]
    fds = [os.open(p, os.O_WRONLY | os.O_NONBLOCK) for p in sys.argv[3:]]
    tick = 0
    next_t = time.monotonic()
    while True:
        for i, fd in enumerate(fds):
            lines = "".join(f"@{a} monitor 0D01 {100 + (tick * 7 + i + a) % 300} 388\n"
                            for a in addresses)
            try:
                os.write(fd, lines.encode())
            except BlockingIOError:
                pass  # a simulator behind: skip this tick for it
        tick += 1
        next_t += period
        delay = next_t - time.monotonic()
        if delay > 0:
            time.sleep(delay)
        else:
            next_t = time.monotonic()


if __name__ == "__main__":
    main()
