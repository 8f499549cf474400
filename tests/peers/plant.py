"""A plant for Vigie's integration tests: a pymodbus Modbus TCP server on 127.0.0.1.

Sensors are discrete inputs 0..31, actuators coils 0..31 (unit 1), like the sorting
station's io-map. `--mirror C:D,...` wires mirror contacts: a write to coil C sets
discrete input D in the same request (a contactor's auxiliary contact, read by the next
scan); `di` still sets any input by hand (a welded or dead contactor). Driven line by line on stdin, answers on stdout:
  di ADDR 0|1     set a discrete input            -> "ok"
  co ADDR 0|1     set a coil (a plant that exposes commanded outputs) -> "ok"
  coils           the first 16 coils              -> "coils 0100..."
  quit            stop
Prints "listening PORT" once serving. `--port N` reuses a port (restart after a kill).
"""

import argparse
import asyncio
import logging
import socket
import sys

from pymodbus.datastore import (
    ModbusDeviceContext,
    ModbusSequentialDataBlock,
    ModbusServerContext,
)
from pymodbus.server import ModbusTcpServer


class Mirrored:
    """The server's datastore, with coil writes copied to the inputs wired to them."""

    def __init__(self, inner, wiring):
        self.inner = inner
        self.wiring = wiring

    def __getattr__(self, name):
        return getattr(self.inner, name)

    async def async_setValues(self, device_id, func_code, address, values):  # noqa: N802
        result = await self.inner.async_setValues(device_id, func_code, address, values)
        if func_code in (5, 15) and not result:
            for k, v in enumerate(values):
                d = self.wiring.get(address + k)
                if d is not None:
                    await self.inner.async_setValues(device_id, 2, d, [bool(v)])
        return result


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


async def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--mirror", default="", help="C:D,... coil C mirrored on input D")
    args = parser.parse_args()
    wiring = {int(c): int(d) for c, d in (p.split(":") for p in args.mirror.split(",") if p)}
    logging.disable(logging.WARNING)
    port = args.port or free_port()
    device = ModbusDeviceContext(
        di=ModbusSequentialDataBlock(1, [False] * 32),
        co=ModbusSequentialDataBlock(1, [False] * 32),
    )
    server = ModbusTcpServer(ModbusServerContext(devices={1: device}), address=("127.0.0.1", port))
    server.context = Mirrored(server.context, wiring)
    task = asyncio.create_task(server.serve_forever())
    # Wait until the socket accepts connections.
    for _ in range(200):
        try:
            _, w = await asyncio.open_connection("127.0.0.1", port)
            w.close()
            break
        except OSError:
            await asyncio.sleep(0.01)
    print(f"listening {port}", flush=True)
    loop = asyncio.get_running_loop()
    while True:
        line = await loop.run_in_executor(None, sys.stdin.readline)
        words = line.split()
        if not words or words[0] == "quit":
            break
        if words[0] == "di":
            # `di A V [A V ...]`: every pair in one step of the loop, so that a reader
            # sees them change in the same scan.
            pairs = words[1:]
            for a, v in zip(pairs[0::2], pairs[1::2]):
                await server.async_setValues(1, 2, int(a), [v == "1"])
            print("ok", flush=True)
        elif words[0] == "co":
            await server.async_setValues(1, 5, int(words[1]), [words[2] == "1"])
            print("ok", flush=True)
        elif words[0] == "coils":
            values = await server.async_getValues(1, 1, 0, 16)
            print("coils " + "".join("1" if v else "0" for v in values), flush=True)
        else:
            print(f"error unknown command {words[0]}", flush=True)
    await server.shutdown()
    task.cancel()


if __name__ == "__main__":
    asyncio.run(main())
