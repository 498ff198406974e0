#!/usr/bin/env python3
"""Tiny Modbus TCP client for the bench scripts (no dependencies).

mbwrite.py [--wait-online] PORT UNIT:ADDR=V1,V2,...
                                      write holding registers (FC16) on each unit given; with
                                      --wait-online, first wait (10 s at most) for the unit's
                                      online status bit, so start-up handshakes are done
mbwrite.py --read-timeouts PORT UNIT  print '# unit U status=.. timeouts=..' (common block)
mbwrite.py --frames PORT UNIT...      print the sum of frames_good (input 9..10) over the units
"""
import socket
import struct
import sys
import time

ONLINE = 1  # status bit 0 (include/drivegate/common.h)


def request(sock, tid, unit, pdu):
    # MBAP (Modbus Messaging on TCP/IP 3.1.3): tid, protocol 0, length = unit + PDU.
    sock.sendall(struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu)
    head = recv_exactly(sock, 7)
    length = struct.unpack(">H", head[4:6])[0]
    body = recv_exactly(sock, length - 1)
    if body[0] & 0x80:
        raise RuntimeError(f"unit {unit}: exception {body[1]}")
    return body


def recv_exactly(sock, n):
    data = b""
    while len(data) < n:
        more = sock.recv(n - len(data))
        if not more:  # closed: not a gateway, or one going away (never spin on it)
            raise ConnectionError(f"connection closed after {len(data)} of {n} bytes")
        data += more
    return data


def wait_online(sock, unit, seconds=10.0):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            body = request(sock, 1, unit, struct.pack(">BHH", 4, 0, 1))
            if struct.unpack(">H", body[2:4])[0] & ONLINE:
                return
        except RuntimeError:
            pass
        time.sleep(0.1)
    raise RuntimeError(f"unit {unit}: not online after {seconds:.0f} s")


def write(sock, unit, addr, values):
    pdu = struct.pack(">BHHB", 16, addr, len(values), 2 * len(values))
    pdu += b"".join(struct.pack(">H", v & 0xFFFF) for v in values)
    request(sock, 1, unit, pdu)


def main():
    if sys.argv[1] == "--read-timeouts":
        port, unit = int(sys.argv[2]), int(sys.argv[3])
        with socket.create_connection(("127.0.0.1", port)) as s:
            body = request(s, 1, unit, struct.pack(">BHH", 4, 0, 19))
            regs = struct.unpack(">19H", body[2:])
            print(f"# unit {unit} status=0x{regs[0]:04x} fault_code={regs[1]} "
                  f"timeouts={(regs[13] << 16) | regs[14]}")
        return
    if sys.argv[1] == "--frames":
        total = 0
        with socket.create_connection(("127.0.0.1", int(sys.argv[2]))) as s:
            for unit in sys.argv[3:]:
                body = request(s, 1, int(unit), struct.pack(">BHH", 4, 9, 2))
                hi, lo = struct.unpack(">HH", body[2:6])
                total += (hi << 16) | lo
        print(total)
        return
    args = sys.argv[1:]
    wait = args[0] == "--wait-online"
    if wait:
        args = args[1:]
    port = int(args[0])
    failed = False
    with socket.create_connection(("127.0.0.1", port)) as s:
        for spec in args[1:]:
            target, values = spec.split("=")
            unit, addr = (int(x) for x in target.split(":"))
            try:
                if wait:
                    wait_online(s, unit)
                write(s, unit, addr, [int(v) for v in values.split(",")])
            except RuntimeError as e:
                print(f"mbwrite: {e}", file=sys.stderr)
                failed = True
    sys.exit(1 if failed else 0)  # every write is tried; a drive not started spoils the run


if __name__ == "__main__":
    main()
