#!/usr/bin/python3
"""A Modbus RTU / ASCII slave nobody here wrote: pymodbus's serial server (Debian's
python3-pymodbus) holding the registers of the example-vfd profile
(adapters/modbus/profiles/example-vfd.toml), for adapters/modbus/tests/e2e_test.cpp.

Every write it takes is printed on stdout as `write TABLE ADDRESS VALUE...`, so the test sees what
reached the slave. Units other than --unit get no answer at all, as from a slave that is not there.
Its device identification (FC 0x2B / 0x0E) is what --vendor, --product-code and --revision say:
without them, a reply with no object.
"""
import argparse
import asyncio
import struct
import sys

from pymodbus.datastore import ModbusServerContext, ModbusSlaveContext, ModbusSparseDataBlock
from pymodbus.device import ModbusDeviceIdentification
from pymodbus.server import StartAsyncSerialServer
from pymodbus.transaction import ModbusAsciiFramer, ModbusRtuFramer


class Logged(ModbusSparseDataBlock):
    """A sparse block (only the addresses given exist; others answer exception 02) that prints
    every write."""

    def __init__(self, table, values):
        super().__init__(values)
        self.table = table

    def setValues(self, address, values, *args, **kwargs):  # noqa: N802 (pymodbus's name)
        super().setValues(address, values, *args, **kwargs)
        values = values if isinstance(values, list) else [values]
        print(f"write {self.table} {address} " + " ".join(str(int(v)) for v in values),
              flush=True)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--port", required=True)
    p.add_argument("--unit", type=int, default=7)
    p.add_argument("--framing", choices=["rtu", "ascii"], default="rtu")
    p.add_argument("--status", type=int, default=0, help="holding 100: bit 2 run, bit 3 fault")
    p.add_argument("--speed", type=int, default=0, help="input 200, 0.1 rpm")
    p.add_argument("--current", type=float, default=12.5, help="input 202..203, f32, low word first")
    p.add_argument("--fault", type=int, default=0, help="input 210: the native fault number")
    p.add_argument("--no-control", action="store_true", help="no holding 0: writes to it fail")
    p.add_argument("--vendor", help="identification object 0x00, VendorName")
    p.add_argument("--product-code", help="identification object 0x01, ProductCode")
    p.add_argument("--revision", help="identification object 0x02, MajorMinorRevision")
    a = p.parse_args()

    high, low = struct.unpack(">HH", struct.pack(">f", a.current))
    holding = {1: 0, 100: a.status}
    if not a.no_control:
        holding[0] = 0x0006
    # 201 is not a point of the profile but a register of the slave: the profile's max_gap reads
    # through it.
    inputs = {200: a.speed & 0xFFFF, 201: 0, 202: low, 203: high, 210: a.fault}
    slave = ModbusSlaveContext(hr=Logged("holding", holding), ir=Logged("input", inputs),
                               zero_mode=True)
    context = ModbusServerContext(slaves={a.unit: slave}, single=False)
    framer = ModbusRtuFramer if a.framing == "rtu" else ModbusAsciiFramer
    names = {"VendorName": a.vendor, "ProductCode": a.product_code,
             "MajorMinorRevision": a.revision}
    identity = ModbusDeviceIdentification(info_name={k: v for k, v in names.items() if v})
    # A pseudo-terminal carries bytes, not bits on a wire, and Linux refuses a parity setting on
    # some (tcsetattr: EINVAL): this end is opened 8N1; the daemon's end is set as the bus says.
    asyncio.run(serve(context=context, framer=framer, identity=identity, port=a.port,
                      baudrate=19200, parity="N", stopbits=1, bytesize=8,
                      ignore_missing_slaves=True))
    return 0


async def serve(**kwargs):
    """Opens the port, says `ready` (from then on a request is heard), and answers forever."""
    server = await StartAsyncSerialServer(defer_start=True, **kwargs)
    await server.start()
    print("ready", flush=True)
    await server.serve_forever()


if __name__ == "__main__":
    sys.exit(main())
