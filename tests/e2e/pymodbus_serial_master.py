#!/usr/bin/python3
"""A Modbus RTU / ASCII master nobody here wrote: pymodbus's serial client (Debian's
python3-pymodbus), or with --tcp its TCP client sending RTU / ASCII frames ("RTU over TCP"), for
tests/e2e/serial_listener_e2e_test.cpp. Runs the steps given on the command
line in order, one line of output each:

  read UNIT TABLE ADDRESS COUNT   TABLE: holding or input -> "ok V..." | "exception N" | "none"
  write UNIT ADDRESS VALUE        FC 06                   -> "ok" | "exception N" | "none"
  writes UNIT ADDRESS V,V,...     FC 16                   -> as write
  raw HEX                         bytes as they are (noise, half a frame): "reply HEX" (what came
                                  back within 300 ms, "" if none)
  rtu UNIT HEX                    the PDU HEX to UNIT with its CRC (a broadcast, FC 08): as raw
  ascii UNIT HEX                  the PDU HEX to UNIT as an ASCII frame (':', hex, LRC, CR LF):
                                  as raw, but done at the reply's CR LF; with --ascii-wait MS
                                  waits up to MS for it (a loaded machine's late reply is then
                                  not taken for silence, nor heard by the next step)
  listen MS                       sends nothing: "heard HEX", what came within MS ("" if none)
  sleep MS
"""
import argparse
import sys
import time

import serial
from pymodbus.client import ModbusSerialClient, ModbusTcpClient
from pymodbus.transaction import ModbusAsciiFramer, ModbusRtuFramer


def crc16(data):
    """CRC-16/MODBUS (MODBUS over Serial Line V1.02, 6.2.2), low byte first on the wire."""
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return bytes([crc & 0xFF, crc >> 8])


def ascii_frame(body):
    """MODBUS over Serial Line V1.02, 2.5.2.1: ':', the bytes and their LRC (6.2.1) in hex,
    CR LF."""
    lrc = (-sum(body)) & 0xFF
    return b":" + (body + bytes([lrc])).hex().upper().encode() + b"\r\n"


def answer(r):
    if r is None or getattr(r, "isError", lambda: True)():
        code = getattr(r, "exception_code", None)
        return f"exception {code}" if code is not None else "none"
    regs = getattr(r, "registers", None)
    return "ok" + ("" if regs is None else " " + " ".join(str(v) for v in regs))


def frame_of(op, steps):
    """The bytes a raw, rtu or ascii step sends, its arguments taken from `steps`."""
    if op == "raw":
        return bytes.fromhex(steps.pop(0))
    body = bytes([int(steps.pop(0))]) + bytes.fromhex(steps.pop(0))
    return body + crc16(body) if op == "rtu" else ascii_frame(body)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--port", help="the master's end of the line")
    p.add_argument("--tcp", help="host:port: RTU / ASCII frames over TCP instead")
    p.add_argument("--framing", choices=["rtu", "ascii"], default="rtu")
    p.add_argument("--ascii-wait", type=int, help="ms an ascii step waits for its reply's CR LF")
    p.add_argument("steps", nargs="*")
    a = p.parse_args()
    framer = ModbusRtuFramer if a.framing == "rtu" else ModbusAsciiFramer
    # A pseudo-terminal refuses some parity settings (tcsetattr: EINVAL): this end is 8N1, the
    # daemon's end is set as its listener says (pymodbus_serial_slave.py does the same).
    if a.tcp:
        host, port = a.tcp.rsplit(":", 1)
        c = ModbusTcpClient(host, port=int(port), framer=framer, timeout=1, retries=0)
    else:
        c = ModbusSerialClient(port=a.port, framer=framer, baudrate=19200, parity="N", stopbits=1,
                               bytesize=8, timeout=1, retries=0)
    if not c.connect():
        print("cannot open", a.port or a.tcp, flush=True)
        return 1
    steps = list(a.steps)
    while steps:
        op = steps.pop(0)
        try:
            if op == "read":
                unit, table, address, count = int(steps.pop(0)), steps.pop(0), int(steps.pop(0)), \
                    int(steps.pop(0))
                f = c.read_holding_registers if table == "holding" else c.read_input_registers
                print(answer(f(address, count, slave=unit)), flush=True)
            elif op == "write":
                unit, address, value = int(steps.pop(0)), int(steps.pop(0)), int(steps.pop(0))
                print(answer(c.write_register(address, value, slave=unit)), flush=True)
            elif op == "writes":
                unit, address = int(steps.pop(0)), int(steps.pop(0))
                values = [int(v) for v in steps.pop(0).split(",")]
                print(answer(c.write_registers(address, values, slave=unit)), flush=True)
            elif op in ("raw", "rtu", "ascii") and a.tcp:
                data = frame_of(op, steps)
                if c.socket is None:  # pymodbus closes the socket after a request timed out
                    c.connect()
                s = c.socket
                s.sendall(data)
                s.settimeout(0.3)
                got = b""
                try:
                    while True:
                        chunk = s.recv(256)
                        if not chunk:
                            break
                        got += chunk
                except OSError:
                    pass
                print("reply " + got.hex(), flush=True)
            elif op in ("raw", "rtu", "ascii"):
                data = frame_of(op, steps)
                s = c.socket
                s.reset_input_buffer()
                s.write(data)
                s.flush()
                until_crlf = op == "ascii" and a.ascii_wait is not None
                deadline = time.monotonic() + (a.ascii_wait if until_crlf else 300) / 1000
                got = b""
                while time.monotonic() < deadline and not (until_crlf and got.endswith(b"\r\n")):
                    chunk = s.read(256)
                    got += chunk
                print("reply " + got.hex(), flush=True)
            elif op == "listen" and not a.tcp:
                deadline = time.monotonic() + int(steps.pop(0)) / 1000
                got = b""
                while time.monotonic() < deadline:
                    got += c.socket.read(256)
                print("heard " + got.hex(), flush=True)
            elif op == "sleep":
                time.sleep(int(steps.pop(0)) / 1000)
            else:
                print("unknown step", op, flush=True)
                return 2
        except Exception as e:  # a step that raised says so and the next one runs
            print("error", type(e).__name__, e, flush=True)
    c.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
