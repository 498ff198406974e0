#!/usr/bin/env python3
"""Writes the seed corpora from the project's golden vectors: tests/fuzz/corpus/<target>/ for the
core's targets, adapters/<id>/fuzz/corpus/ for adapter_<id> (every adapter with a fuzz/ folder).

Every brace-enclosed byte list of 3 or more 0xNN bytes in an adapter's codec test
(adapters/<id>/tests/codec_test.cpp) becomes a codec,
a driver and a simulator seed (the adapter target's mode byte and script around it); every request
PDU of tests/modbus/pdu_test.cpp (`run({...})`, the Application Protocol's own examples) becomes an
MBAP frame for unit 1, alone and all together in one stream; configurations come from
etc/drivegate.toml and the raw-string configs of tests/config/config_test.cpp; Telnet / RFC 2217
streams from tests/transport/telnet_codec_test.cpp. Re-run after the
vectors change: python3 tests/fuzz/make_seeds.py
"""
import hashlib
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "tests" / "fuzz" / "corpus"
BYTES = re.compile(r"\{\s*((?:0x[0-9A-Fa-f]{2}\s*,\s*){2,}0x[0-9A-Fa-f]{2})\s*,?\s*\}")


HEX = re.compile(r'hex\("((?:[0-9A-Fa-f]{2} ){2,}[0-9A-Fa-f]{2})"\)')


def vectors(path):
    text = path.read_text()
    for m in BYTES.finditer(text):
        yield bytes(int(b, 16) for b in re.findall(r"0x([0-9A-Fa-f]{2})", m.group(1)))
    # The framed adapter's tests write frames as hex("A5 05 00 ...").
    for m in HEX.finditer(text):
        yield bytes.fromhex(m.group(1))


def write(target, data):
    d = target if isinstance(target, pathlib.Path) else OUT / target
    d.mkdir(parents=True, exist_ok=True)
    (d / ("seed-" + hashlib.sha1(data).hexdigest()[:16])).write_bytes(data)


def chunk(op, data):
    # adapter_fuzz.cpp: an op byte, a length byte, then that many bytes.
    out = b""
    for i in range(0, len(data), 255):
        part = data[i:i + 255]
        out += bytes([op, len(part)]) + part
    return out


def adapter_seeds(adapter):
    target = ROOT / "adapters" / adapter / "fuzz" / "corpus"
    test = ROOT / "adapters" / adapter / "tests" / "codec_test.cpp"
    vecs = sorted(set(vectors(test)))
    # Codec prefix: ed3100 first reads a reply shape (function index, register, words).
    shape = bytes([0, 0x00, 0x06, 1]) if adapter == "ed3100" else b""
    for v in vecs:
        write(target, b"\x00" + shape + v)
        # Driver: default address, 500 ms polls, not maintenance; ask for an exchange, hear the
        # vector, run forward at 1000 rpm, take completions, let 600 ms pass, poll again.
        script = (b"\x00" + chunk(1, v) + b"\x03\x01" + b"\x04\x03\xe8" + b"\x08" +
                  b"\x02\x02\x58" + b"\x00" + chunk(1, v) + b"\x08")
        write(target, bytes([1, 0x00, 45, 0]) + script)
        # Simulator: hear the vector, tick 100 ms, ask for its state.
        write(target, bytes([2, 0x00]) + chunk(0, v) + b"\x02\x00\x64" + b"\x03\x05state")
    write(target, bytes([1, 0x00, 45, 0]) + b"\x00\x02\x10\x00\x00\x06\x07\x08")
    # The modbus adapter's codec mode also reads its input as a profile: the shipped ones.
    for profile in sorted((ROOT / "adapters" / adapter / "profiles").glob("*.toml")):
        write(target, b"\x00" + profile.read_bytes())
    # The framed adapter's codec mode picks a shipped description (in name order) for the bytes,
    # or, one past them, reads the rest as a description: the shipped ones.
    descriptions = sorted((ROOT / "adapters" / adapter / "protocols").glob("*.toml"))
    for pick in range(len(descriptions)):
        for v in vecs:
            write(target, bytes([0, pick]) + v)
    for description in descriptions:
        write(target, bytes([0, len(descriptions)]) + description.read_bytes())


def mbap(transaction, unit, pdu):
    return (transaction.to_bytes(2, "big") + b"\x00\x00" + (len(pdu) + 1).to_bytes(2, "big") +
            bytes([unit]) + pdu)


def modbus_seeds():
    text = (ROOT / "tests" / "modbus" / "pdu_test.cpp").read_text()
    pdus = []
    for m in re.finditer(r"run\(\s*\{([^}]*)\}", text):
        found = re.findall(r"0x([0-9A-Fa-f]{2})", m.group(1))
        if found:
            pdus.append(bytes(int(b, 16) for b in found))
    stream = b""
    for i, pdu in enumerate(pdus):
        frame = mbap(i + 1, 1, pdu)
        stream += frame
        for target in ("modbus_fake", "modbus_gateway"):
            write(target, b"\x00" + frame)
    for target in ("modbus_fake", "modbus_gateway"):
        write(target, b"\x00" + stream)   # one segment, writes complete at once
        write(target, b"\x09" + stream)   # one byte at a time, writes deferred
    # The gateway: the common block of every unit (docs/register-map.md), and writes to it.
    for unit in range(1, 8):
        write("modbus_gateway", b"\x00" + mbap(unit, unit, bytes([0x04, 0, 0, 0, 32])) +
              mbap(unit, unit, bytes([0x03, 0, 0, 0, 16])) +
              mbap(unit, unit, bytes([0x10, 0, 0, 0, 2, 4, 0, 1, 0x03, 0xE8])) +
              mbap(unit, unit, bytes([0x06, 0, 0, 0, 0])))


def config_seeds():
    write("config", (ROOT / "etc" / "drivegate.toml").read_bytes())
    text = (ROOT / "tests" / "config" / "config_test.cpp").read_text()
    for m in re.finditer(r'R"\((.*?)\)"', text, re.S):
        write("config", m.group(1).encode())


def telnet_seeds():
    """The Telnet / RFC 2217 codec's golden vectors (tests/transport/telnet_codec_test.cpp), each after
    the target's option byte: whole (0) and in 1- and 3-byte segments."""
    for stream in vectors(ROOT / "tests" / "transport" / "telnet_codec_test.cpp"):
        for option in (0, 1, 3):
            write("telnet_stream", bytes([option]) + stream)
    # A device server's greeting and its answers to drivegate's configure() (RFC 2217 section
    # "Com Port Configuration Commands": the code + 100 and the value in use), then data with an
    # escaped 0xFF, split one byte at a time.
    iac, sb, se = 255, 250, 240
    answers = bytes([iac, 251, 44, iac, 253, 0, iac, 251, 3])
    for code, value in ((101, b"\x00\x00\x25\x80"), (102, b"\x08"), (103, b"\x03"), (104, b"\x01"),
                        (105, b"\x01")):
        answers += bytes([iac, sb, 44, code]) + value + bytes([iac, se])
    answers += b"\x01\x03\xff\xff\x10"
    for option in (0, 1):
        write("telnet_stream", bytes([option]) + answers)


def main():
    for adapter in sorted(p.name for p in (ROOT / "adapters").iterdir() if p.is_dir()):
        folder = ROOT / "adapters" / adapter
        if (folder / "fuzz").is_dir() and (folder / "tests" / "codec_test.cpp").exists():
            adapter_seeds(adapter)
    modbus_seeds()
    config_seeds()
    telnet_seeds()


if __name__ == "__main__":
    main()
