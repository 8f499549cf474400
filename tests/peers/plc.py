"""A PLC for Vigie's integration tests: a pymodbus Modbus TCP client that, every
period, reads the sensors (discrete inputs 0..10) and writes its commanded coils 0..6,
like a PLC scan. Driven line by line on stdin, answers on stdout:
  coils 0101000   set the commanded coils        -> "ok"
  di              the last sensors read          -> "di 0100..."
  status          counts of scans and errors     -> "status SCANS ERRORS LAST_ERROR"
  raw FC ADDR N   one request outside the scan   -> "exception CODE" or "ok VALUES"
  quit            stop
`--source IP` binds the client to a loopback source address (127.0.0.2) so that the
server's allow-list and writer checks can tell clients apart.
"""

import argparse
import logging
import sys
import threading
import time

from pymodbus.client import ModbusTcpClient


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--source", default=None)
    parser.add_argument("--period-ms", type=float, default=5.0)
    parser.add_argument("--sensors", type=int, default=11)
    parser.add_argument("--coils", type=int, default=7)
    args = parser.parse_args()
    logging.disable(logging.CRITICAL)
    source = (args.source, 0) if args.source else None
    client = ModbusTcpClient("127.0.0.1", port=args.port, source_address=source, timeout=1, retries=0)
    lock = threading.Lock()
    state = {"coils": [False] * args.coils, "di": [False] * args.sensors, "scans": 0, "errors": 0, "last": "-", "stop": False}

    def scan_loop() -> None:
        while not state["stop"]:
            with lock:  # one request at a time on the client, and the state with it
                try:
                    if not client.connected:
                        client.connect()
                    r = client.read_discrete_inputs(0, count=args.sensors, device_id=1)
                    if r.isError():
                        state["errors"] += 1
                        state["last"] = f"read:{getattr(r, 'exception_code', r)}"
                    else:
                        state["di"] = list(r.bits[: args.sensors])
                    w = client.write_coils(0, list(state["coils"]), device_id=1)
                    if w.isError():
                        state["errors"] += 1
                        state["last"] = f"write:{getattr(w, 'exception_code', w)}"
                    state["scans"] += 1
                except Exception as e:  # noqa: BLE001 - a test peer reports, never dies
                    state["errors"] += 1
                    state["last"] = type(e).__name__
                    client.close()
            time.sleep(args.period_ms / 1000)

    thread = threading.Thread(target=scan_loop, name="scan", daemon=True)
    thread.start()
    print("running", flush=True)
    for line in sys.stdin:
        words = line.split()
        if not words or words[0] == "quit":
            break
        with lock:
            if words[0] == "coils":
                state["coils"] = [c == "1" for c in words[1]]
                print("ok", flush=True)
            elif words[0] == "di":
                print("di " + "".join("1" if v else "0" for v in state["di"]), flush=True)
            elif words[0] == "status":
                print(f"status {state['scans']} {state['errors']} {state['last'].replace(' ', '_')}", flush=True)
            elif words[0] == "raw":
                fc, addr, n = int(words[1]), int(words[2]), int(words[3])
                try:
                    if fc == 1:
                        r = client.read_coils(addr, count=n, device_id=1)
                    elif fc == 2:
                        r = client.read_discrete_inputs(addr, count=n, device_id=1)
                    elif fc == 15:
                        r = client.write_coils(addr, [True] * n, device_id=1)
                    else:
                        r = client.read_holding_registers(addr, count=n, device_id=1)
                    if r.isError():
                        print(f"exception {r.exception_code}", flush=True)
                    else:
                        print("ok " + "".join("1" if b else "0" for b in getattr(r, "bits", [])[:n]), flush=True)
                except Exception as e:  # noqa: BLE001
                    print(f"error {type(e).__name__}", flush=True)
            else:
                print(f"error unknown command {words[0]}", flush=True)
    state["stop"] = True
    thread.join(timeout=2)
    client.close()


if __name__ == "__main__":
    main()
