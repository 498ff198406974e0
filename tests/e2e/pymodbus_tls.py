#!/usr/bin/python3
"""A Modbus/TCP Security client for the end-to-end tests: pymodbus over TLS with a client
certificate, driven one action per line on stdin, one JSON line per result on stdout.

Usage: /usr/bin/python3 pymodbus_tls.py HOST PORT CA CERT KEY [UNIT]   (CERT and KEY "-": none)

First line out, once the TLS session is up and the server had time to refuse the certificate
(TLS 1.3 clients finish their handshake before the server has judged their certificate):
  {"connect": "ok", "tls": "TLSv1.3"}  or  {"connect": "failed", "error": "...", "ssl": true}
Then, for each line in (until EOF):
  read_input ADDR COUNT | read_holding ADDR COUNT  ->  {"op": ..., "registers": [...]}
  write ADDR VALUE  (function 06)                  ->  {"op": "write", "ok": true}
  a Modbus exception                               ->  {"op": ..., "exception": CODE}
  anything else (connection lost, timeout)         ->  {"op": ..., "error": "...", "ssl": bool}

The Modbus/TCP Security spec carries the MBAP ADU unchanged inside TLS; pymodbus's default
ModbusTlsFramer leaves the MBAP out (pymodbus issue #2014), hence ModbusSocketFramer. The sync
ModbusTlsClient misses replies buffered inside the SSL object, hence the async client.
"""
import asyncio
import json
import ssl
import sys

from pymodbus.client import AsyncModbusTlsClient
from pymodbus.framer.socket_framer import ModbusSocketFramer
from pymodbus.pdu import ExceptionResponse

# How long the server has to refuse a certificate after the client's side of the handshake.
VERDICT_WAIT_S = 0.3


class Client(AsyncModbusTlsClient):
    """pymodbus's async TLS client, but connect errors are raised instead of retried, a lost
    connection is not reopened, and why it was lost is kept (an ssl.SSLError for an alert)."""

    lost_reason = None

    def _create_protocol(self):
        protocol = super()._create_protocol()
        on_lost = protocol.connection_lost

        def connection_lost(reason):
            self.lost_reason = reason
            on_lost(reason)

        protocol.connection_lost = connection_lost
        return protocol

    def protocol_lost_connection(self, protocol):
        self.connected = False
        self.protocol = None

    async def _connect(self):
        return await self.loop.create_connection(
            self._create_protocol, self.params.host, self.params.port, ssl=self.sslctx
        )


def out(**fields):
    print(json.dumps(fields), flush=True)


def describe(exc):
    return {"error": f"{type(exc).__name__}: {exc}", "ssl": isinstance(exc, ssl.SSLError)}


async def run_action(client, unit, words):
    op = words[0]
    try:
        if op in ("read_input", "read_holding"):
            address, count = int(words[1]), int(words[2])
            read = client.read_input_registers if op == "read_input" else client.read_holding_registers
            rr = await read(address, count, slave=unit)
        elif op == "write":
            rr = await client.write_register(int(words[1]), int(words[2]), slave=unit)
        else:
            out(op=op, error="unknown action")
            return
    except Exception as exc:  # pylint: disable=broad-except
        reason = client.lost_reason if client.lost_reason is not None else exc
        out(op=op, **describe(reason))
        return
    if isinstance(rr, ExceptionResponse):
        out(op=op, exception=rr.exception_code)
    elif op == "write":
        out(op=op, ok=True)
    else:
        out(op=op, registers=list(rr.registers))


async def main():
    host, port, ca, cert, key = sys.argv[1:6]
    unit = int(sys.argv[6]) if len(sys.argv) > 6 else 1
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)  # verifies the server against CA and host name
    ctx.load_verify_locations(ca)
    if cert != "-":  # "-": no client certificate at all
        ctx.load_cert_chain(cert, key)
    client = Client(host, port=int(port), sslctx=ctx, framer=ModbusSocketFramer,
                    timeout=5, retries=0)
    try:
        transport, _ = await client.connect()
    except Exception as exc:  # pylint: disable=broad-except
        out(connect="failed", **describe(exc))
        return
    await asyncio.sleep(VERDICT_WAIT_S)
    if not client.connected:
        out(connect="failed", **describe(client.lost_reason or ConnectionError("closed")))
        return
    out(connect="ok", tls=transport.get_extra_info("ssl_object").version())
    loop = asyncio.get_running_loop()
    while True:
        line = await loop.run_in_executor(None, sys.stdin.readline)
        if not line:
            break
        if line.split():
            await run_action(client, unit, line.split())
    await client.close()


if __name__ == "__main__":
    asyncio.run(main())
