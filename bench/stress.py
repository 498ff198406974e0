#!/usr/bin/env python3
"""bench/stress.py: the write-storm figures, measured side by side in one run (bench/stress.sh).

Write storm. Two ED3100s on one simulated 9600 8E1 line (units 1 and 2, poll_ms 300, one monitor
each), drive 1 running. Phases of DURATION seconds, for WRITERS in "0 1 4" (each writer one
connection keeping two FC06 setpoint writes to unit 1 in flight), the order rotated each round:
  - neighbour frames/s: unit 2's frames_good over the phase (its polls: two reads a cycle)
  - drive-1 data age: the largest data_age_ms a PLC reads for unit 1 (polled every 50 ms)
  - writes/s taken, refused busy (0x06), other exceptions
  - Modbus p50 / p99: dg-loadgen, one connection reading unit 2's common block (FC04 0..18)
    throughout the phase, on the load CPU; the daemon on the server CPU.

Rebirth storm (REBIRTH=1, needs mosquitto and tests/mqtt/peer's node_modules): the same gateway
with [mqtt] on a local mosquitto; phases without and with 2000 NCMD rebirth requests published
back to back at the phase's start; Modbus p50 / p99 as above, and the NBIRTHs the storm caused.

Sick neighbour (SICK=1): two example-vfd profile devices on one simulated 19200 8E1 line
(`drivegate sim modbus`, addresses 1 and 2, poll_ms 100: four blocks a cycle each). Phases of
DURATION seconds, the order rotated each round: the line healthy, then device 2 silent, answering
1.1 s late, or answering every other request (the simulator's operator commands):
  - healthy frames/s: device 1's frames_good over the phase, and its share of the healthy line's
  - healthy worst data age: the largest data_age_ms a PLC reads for device 1 (every 50 ms), and
    its ratio to the healthy line's
  - sick frames/s: device 2's frames_good over the phase

Nothing here asserts: it prints medians over the rounds (docs/performance.md).
"""
import os
import shutil
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time

BIN = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.abspath("build-bench/bin")
ROUNDS = int(os.environ.get("ROUNDS", "4"))
DURATION = float(os.environ.get("DURATION", "6"))
WRITERS = [int(x) for x in os.environ.get("WRITERS", "0 1 4").split()]
SERVER_CPU = os.environ.get("SERVER_CPU", "0")
LOAD_CPU = os.environ.get("LOAD_CPU", "1")
REBIRTH = os.environ.get("REBIRTH", "1") == "1"
STORM = os.environ.get("STORM", "1") == "1"
SICK = os.environ.get("SICK", "1") == "1"
HERE = os.path.dirname(os.path.abspath(__file__))
PEER = os.path.join(HERE, "..", "tests", "mqtt", "peer", "sparkplug_peer.js")
PLUGINS = os.path.join(BIN, "..", "adapters")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pinned(cpu, argv, **kw):
    return subprocess.Popen(["taskset", "-c", cpu] + argv, **kw)


# The daemons' and simulators' port locks in a directory of the bench's, never in /run/lock: a
# killed bench must not leave stale locks a service's user cannot remove.
LOCK_DIR = tempfile.mkdtemp(prefix="dg-stress-locks-")
os.environ["DRIVEGATE_LOCK_DIR"] = LOCK_DIR


class Modbus:
    """One blocking Modbus TCP connection (MBAP, Messaging on TCP/IP 3.1.3)."""

    def __init__(self, port):
        self.sock = socket.create_connection(("127.0.0.1", port))
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.tid = 0

    def request(self, unit, pdu):
        self.tid = (self.tid + 1) & 0xFFFF
        self.sock.sendall(struct.pack(">HHHB", self.tid, 0, len(pdu) + 1, unit) + pdu)
        head = self.recv(7)
        return self.recv(struct.unpack(">H", head[4:6])[0] - 1)

    def recv(self, n):
        data = b""
        while len(data) < n:
            more = self.sock.recv(n - len(data))
            if not more:
                raise ConnectionError("closed")
            data += more
        return data

    def inputs(self, unit, address, count):
        body = self.request(unit, struct.pack(">BHH", 4, address, count))
        if body[0] & 0x80:
            raise RuntimeError(f"exception {body[1]}")
        return struct.unpack(f">{count}H", body[2:])

    def write(self, unit, address, values):
        pdu = struct.pack(">BHHB", 16, address, len(values), 2 * len(values))
        body = self.request(unit, pdu + struct.pack(f">{len(values)}H", *values))
        if body[0] & 0x80:
            raise RuntimeError(f"exception {body[1]}")


def common(m, unit):
    r = m.inputs(unit, 0, 11)
    return {"status": r[0], "age": (r[7] << 16) | r[8], "frames": (r[9] << 16) | r[10]}


def writer(port, stop, counts):
    """Keeps two FC06 setpoint writes to unit 1 in flight until `stop`; counts the answers."""
    s = socket.create_connection(("127.0.0.1", port))
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    tid, in_flight, buf = 0, 0, b""
    while True:
        while not stop.is_set() and in_flight < 2:
            tid = (tid + 1) & 0xFFFF
            rpm = 1000 + 200 * (tid % 2)
            s.sendall(struct.pack(">HHHBBHH", tid, 0, 6, 1, 6, 1, rpm))
            in_flight += 1
        if in_flight == 0:
            break
        buf += s.recv(4096)
        while len(buf) >= 9:
            size = 6 + struct.unpack(">H", buf[4:6])[0]
            if len(buf) < size:
                break
            fc, code = buf[7], buf[8]
            key = "ok" if not fc & 0x80 else ("busy" if code == 6 else "other")
            counts[key] = counts.get(key, 0) + 1
            buf = buf[size:]
            in_flight -= 1
    s.close()


def loadgen(port, pid, seconds):
    out = subprocess.run(
        ["taskset", "-c", LOAD_CPU, os.path.join(BIN, "dg-loadgen"), "--port", str(port), "--pid",
         str(pid), "--connections", "1", "--duration", str(seconds), "--warmup", "0.2",
         "--unit", "2", "--large", "4:0:19", "--small", "4:0:19"],
        capture_output=True, text=True, check=True).stdout
    return dict(kv.split("=") for kv in out.split())


def start_line(work, sim_args, bus_toml, device_toml, extra_toml=""):
    """A simulator with devices 1 and 2 on a line, the gateway polling both (`device_toml` for a
    unit: its adapter, poll and options), both online; its port, daemon, simulator and a PLC."""
    line = os.path.join(work, "line")
    sim = pinned(LOAD_CPU, [os.path.join(BIN, "drivegate"), "sim"] + sim_args +
                 ["--plugin-dir", PLUGINS, "--address", "1", "--address", "2", "--link", line],
                 stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                 text=True)
    for _ in range(50):
        if os.path.exists(line):
            break
        time.sleep(0.1)
    port = free_port()
    toml = f'[[listener]]\naddress = "127.0.0.1:{port}"\naccess = "operate"\n'
    toml += f'\n[[bus]]\nname = "line"\nport = "{line}"\n{bus_toml}'
    for unit in (1, 2):
        toml += f'\n[[device]]\nbus = "line"\nunit_id = {unit}\naddress = {unit}\n'
        toml += device_toml(unit)
    toml += extra_toml
    path = os.path.join(work, "drivegate.toml")
    with open(path, "w") as f:
        f.write(toml)
    daemon = pinned(SERVER_CPU, [os.path.join(BIN, "drivegated"), "--config", path,
                                 "--plugin-dir", PLUGINS, "--log-level", "warn"],
                    stdout=subprocess.DEVNULL, stderr=open(os.path.join(work, "daemon.log"), "w"))
    for _ in range(100):
        try:
            m = Modbus(port)
            if all(common(m, u)["status"] & 1 for u in (1, 2)):
                break
        except (OSError, RuntimeError):
            pass
        time.sleep(0.1)
    else:
        sys.exit("stress.py: the gateway did not come online; see " + work)
    return port, daemon, sim, m


def start_gateway(work, extra_toml=""):
    """Two ED3100s, drive 1 running."""
    port, daemon, sim, m = start_line(
        work, ["ed3100"], "",
        lambda unit: (f'name = "ed-{unit}"\nadapter = "ed3100"\npoll_ms = 300\n'
                      '[device.options]\nmonitors = ["0D00:Hz"]\n'), extra_toml)
    m.write(1, 0, [1, 1000])  # drive 1 runs: each setpoint goes to the drive
    time.sleep(1)
    return port, daemon, sim, m


def storm_phase(port, pid, m, writers):
    stop, counts, threads = threading.Event(), {}, []
    for _ in range(writers):
        t = threading.Thread(target=writer, args=(port, stop, counts))
        t.start()
        threads.append(t)
    result = {}
    lg = threading.Thread(target=lambda: result.update(loadgen(port, pid, DURATION)))
    f0, worst_age, t0 = common(m, 2)["frames"], 0, time.monotonic()
    lg.start()
    while time.monotonic() - t0 < DURATION:
        worst_age = max(worst_age, common(m, 1)["age"])
        time.sleep(0.05)
    frames = (common(m, 2)["frames"] - f0) / (time.monotonic() - t0)
    stop.set()
    for t in threads:
        t.join()
    lg.join()
    return {"frames_s": frames, "age_ms": worst_age, "ok_s": counts.get("ok", 0) / DURATION,
            "busy_s": counts.get("busy", 0) / DURATION, "other": counts.get("other", 0),
            "p50_us": float(result["p50_us"]), "p99_us": float(result["p99_us"]),
            "p999_us": float(result["p999_us"])}


def med(rows, key):
    return statistics.median(r[key] for r in rows)


def write_storm():
    with tempfile.TemporaryDirectory(prefix="dg-stress-") as work:
        port, daemon, sim, m = start_gateway(work)
        try:
            rows = {n: [] for n in WRITERS}
            for rnd in range(ROUNDS):
                order = WRITERS[rnd % len(WRITERS):] + WRITERS[:rnd % len(WRITERS)]
                for n in order:
                    rows[n].append(storm_phase(port, daemon.pid, m, n))
                    print(f"# round {rnd + 1} writers {n}: {rows[n][-1]}", file=sys.stderr)
        finally:
            daemon.terminate()
            sim.terminate()
            daemon.wait()
    rest = med(rows[0], "frames_s") if 0 in rows else None
    print("\nwrite storm (median of %d rounds of %.0f s)" % (ROUNDS, DURATION))
    print("| writers (2 in flight each) | neighbour frames/s | of rest | drive-1 worst data age "
          "| writes taken /s | refused busy /s | other | Modbus p50 | p99 | p99.9 |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for n in WRITERS:
        r = rows[n]
        share = f"{med(r, 'frames_s') / rest:.2f}" if rest else "-"
        print(f"| {n} | {med(r, 'frames_s'):.2f} | {share} | {med(r, 'age_ms'):.0f} ms "
              f"| {med(r, 'ok_s'):.1f} | {med(r, 'busy_s'):.1f} | {sum(x['other'] for x in r)} "
              f"| {med(r, 'p50_us') / 1000:.3f} ms | {med(r, 'p99_us') / 1000:.3f} ms "
              f"| {med(r, 'p999_us') / 1000:.3f} ms |")


def rebirth_storm():
    mosquitto = "/usr/sbin/mosquitto"
    if not (os.access(mosquitto, os.X_OK) and os.path.isdir(os.path.join(os.path.dirname(PEER),
                                                                         "node_modules"))):
        print("\nrebirth storm: skipped (mosquitto or the peer's node_modules missing)")
        return
    with tempfile.TemporaryDirectory(prefix="dg-rebirth-") as work:
        mport = free_port()
        conf = os.path.join(work, "mosquitto.conf")
        with open(conf, "w") as f:
            f.write(f"listener {mport} 127.0.0.1\nallow_anonymous true\npersistence false\n"
                    + ("user root\n" if os.geteuid() == 0 else ""))
        broker = pinned(LOAD_CPU, [mosquitto, "-c", conf], stdout=subprocess.DEVNULL,
                        stderr=subprocess.DEVNULL)
        time.sleep(0.5)
        mqtt = (f'\n[mqtt]\nbroker = "mqtt://127.0.0.1:{mport}"\ngroup_id = "bench"\n'
                'edge_node_id = "gw"\n')
        port, daemon, sim, m = start_gateway(work, mqtt)
        peer = pinned(LOAD_CPU, ["node", PEER, "--broker", f"mqtt://127.0.0.1:{mport}"],
                      stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        births = {"n": 0}

        def read_peer():
            for line in peer.stdout:
                if line.startswith("msg\tspBv1.0/bench/NBIRTH/gw"):
                    births["n"] += 1
        threading.Thread(target=read_peer, daemon=True).start()
        ncmd = '{"metrics":[{"name":"Node Control/Rebirth","type":"Boolean","value":true}]}'
        rows = {"quiet": [], "2000 NCMD": []}
        try:
            time.sleep(2)
            for rnd in range(ROUNDS):
                for phase in (("quiet", "2000 NCMD") if rnd % 2 == 0 else ("2000 NCMD", "quiet")):
                    before = births["n"]
                    result = {}
                    lg = threading.Thread(
                        target=lambda: result.update(loadgen(port, daemon.pid, DURATION)))
                    lg.start()
                    if phase != "quiet":
                        time.sleep(0.3)
                        peer.stdin.write(f"publish_repeat\tspBv1.0/bench/NCMD/gw\t2000\t{ncmd}\n")
                        peer.stdin.flush()
                    lg.join()
                    rows[phase].append({"p50_us": float(result["p50_us"]),
                                        "p99_us": float(result["p99_us"]),
                                        "p999_us": float(result["p999_us"]),
                                        "births": births["n"] - before})
                    time.sleep(5.5)  # the rebirth interval: each phase starts afresh
        finally:
            for p in (peer, daemon, sim, broker):
                p.terminate()
            daemon.wait()
    print("\nrebirth storm (median of %d rounds of %.0f s)" % (ROUNDS, DURATION))
    print("| phase | Modbus p50 | p99 | p99.9 | NBIRTHs in the phase |")
    print("|---|---|---|---|---|")
    for phase, r in rows.items():
        print(f"| {phase} | {med(r, 'p50_us') / 1000:.3f} ms | {med(r, 'p99_us') / 1000:.3f} ms "
              f"| {med(r, 'p999_us') / 1000:.3f} ms | {med(r, 'births'):.0f} |")


def start_profile_line(work):
    """Two example-vfd slaves on one simulated line, polled every 100 ms."""
    _, daemon, sim, m = start_line(
        work, ["modbus", "--set", "profile=example-vfd"], 'baud = 19200\nparity = "even"\n',
        lambda unit: (f'name = "vfd-{unit}"\nadapter = "modbus"\npoll_ms = 100\n'
                      '[device.options]\nprofile = "example-vfd"\n'))
    return daemon, sim, m


# Each sickness as the simulator's operator commands for device 2: to begin, to end.
SICKNESS = {
    "healthy line": ([], []),
    "silent": (["@2 silent on"], ["@2 silent off"]),
    "1.1 s late": (["@2 late 1100"], ["@2 late 0"]),
    "every other": (["@2 every-other on"], ["@2 every-other off"]),
}


def sick_phase(sim, m, name):
    begin, end = SICKNESS[name]
    for line in begin:
        sim.stdin.write(line + "\n")
    sim.stdin.flush()
    time.sleep(1)  # the sickness takes hold (a first timeout, its back-off)
    f1, f2, worst_age, t0 = common(m, 1)["frames"], common(m, 2)["frames"], 0, time.monotonic()
    while time.monotonic() - t0 < DURATION:
        worst_age = max(worst_age, common(m, 1)["age"])
        time.sleep(0.05)
    span = time.monotonic() - t0
    row = {"frames_s": (common(m, 1)["frames"] - f1) / span, "age_ms": worst_age,
           "sick_s": (common(m, 2)["frames"] - f2) / span}
    for line in end:
        sim.stdin.write(line + "\n")
    sim.stdin.flush()
    # Device 2 back: answering, its back-off and comm_lost over, before the next phase.
    for _ in range(200):
        if common(m, 2)["status"] & 1 and common(m, 2)["age"] < 1000:
            break
        time.sleep(0.1)
    time.sleep(1)
    return row


def sick_neighbour():
    with tempfile.TemporaryDirectory(prefix="dg-sick-") as work:
        daemon, sim, m = start_profile_line(work)
        names = list(SICKNESS)
        rows = {n: [] for n in names}
        try:
            time.sleep(1)
            for rnd in range(ROUNDS):
                for n in names[rnd % len(names):] + names[:rnd % len(names)]:
                    rows[n].append(sick_phase(sim, m, n))
                    print(f"# round {rnd + 1} {n}: {rows[n][-1]}", file=sys.stderr)
        finally:
            daemon.terminate()
            sim.terminate()
            daemon.wait()
    base = rows["healthy line"]
    print("\nsick neighbour (median of %d rounds of %.0f s; device 1 healthy, device 2 as said)"
          % (ROUNDS, DURATION))
    print("| device 2 | device 1 frames/s | of the healthy line | device 1 worst data age "
          "| of the healthy line | device 2 frames/s |")
    print("|---|---|---|---|---|---|")
    for n in names:
        r = rows[n]
        print(f"| {n} | {med(r, 'frames_s'):.1f} | {med(r, 'frames_s') / med(base, 'frames_s'):.2f} "
              f"| {med(r, 'age_ms'):.0f} ms | {med(r, 'age_ms') / med(base, 'age_ms'):.2f} "
              f"| {med(r, 'sick_s'):.1f} |")


if __name__ == "__main__":
    try:
        if STORM:
            write_storm()
        if REBIRTH:
            rebirth_storm()
        if SICK:
            sick_neighbour()
    finally:
        shutil.rmtree(LOCK_DIR, ignore_errors=True)
