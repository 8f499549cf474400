"""A PLC for Vigie's integration tests: an asyncua OPC UA client that, every period,
reads its inputs (one Read of `--inputs`) and writes its outputs (one Write of
`--outputs`, Booleans), like a PLC scan. Signals are `ns=<idx>;s=<name>`, the index of
`--namespace` looked up in the server's namespace array. Any error is counted and the
connection made anew after a short delay. `--security sign|encrypt` (Basic256Sha256) with
`--cert-dir` (own certificate client_cert.der + client_key.pem, made if absent) and
`--server-cert FILE` (else the server's is taken as offered); `--user`/`--password`
(else anonymous). Driven line by line on stdin, answers on stdout:
  outputs 0101000   set what the scan writes       -> "ok"
  inputs            the last inputs read           -> "inputs 0100..."
  status            counts of scans and errors     -> "status SCANS ERRORS LAST_ERROR"
  write NAME 0|1    one write outside the scan     -> "ok" or "error STATUS"
  read NAME         one read outside the scan      -> "value 0|1" or "error STATUS"
  quit              stop
Prints "running" once started, before any connection.
"""

import argparse
import asyncio
import logging
import sys
from pathlib import Path

from asyncua import Client, ua
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from asyncua.ua.status_codes import get_name_and_doc
from cryptography.x509.oid import ExtendedKeyUsageOID
from opcua_certs import ensure_certificate

APP_URI = "urn:vigie:test:plc"
MODES = {"sign": ua.MessageSecurityMode.Sign, "encrypt": ua.MessageSecurityMode.SignAndEncrypt}


def describe(e: BaseException) -> str:
    if isinstance(e, ua.UaStatusCodeError) and getattr(e, "code", None) is not None:
        return get_name_and_doc(e.code)[0]
    return type(e).__name__


def bits(values) -> str:
    return "".join("1" if v else "0" for v in values)


def boolean(v: bool) -> ua.DataValue:
    return ua.DataValue(ua.Variant(v, ua.VariantType.Boolean))


async def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--endpoint", required=True)
    parser.add_argument("--namespace", required=True)
    parser.add_argument("--inputs", default="")
    parser.add_argument("--outputs", default="")
    parser.add_argument("--period-ms", type=float, default=5.0)
    parser.add_argument("--security", choices=["none", "sign", "encrypt"], default="none")
    parser.add_argument("--cert-dir", type=Path)
    parser.add_argument("--server-cert", type=Path)
    parser.add_argument("--user", default=None)
    parser.add_argument("--password", default=None)
    args = parser.parse_args()
    if args.security != "none" and args.cert_dir is None:
        parser.error("--security other than none needs --cert-dir")
    logging.disable(logging.CRITICAL)
    inputs = [n for n in args.inputs.split(",") if n]
    outputs = [n for n in args.outputs.split(",") if n]
    if args.cert_dir is not None:
        cert, key = args.cert_dir / "client_cert.der", args.cert_dir / "client_key.pem"
        ensure_certificate(cert, key, APP_URI, ExtendedKeyUsageOID.CLIENT_AUTH)
    state = {"outputs": [False] * len(outputs), "inputs": [False] * len(inputs), "scans": 0, "errors": 0, "last": "-"}
    link = {"client": None, "idx": None}
    lock = asyncio.Lock()  # one request at a time on the client

    async def connect() -> None:
        client = Client(args.endpoint, timeout=2)
        client.application_uri = APP_URI
        client.name = client.description = "Vigie test PLC"
        if args.user is not None:
            client.set_user(args.user)
            client.set_password(args.password or "")
        if args.security != "none":
            server_cert = str(args.server_cert) if args.server_cert else None  # None: take the offered one
            policy, mode = SecurityPolicyBasic256Sha256, MODES[args.security]
            await client.set_security(policy, str(cert), str(key), None, server_cert, mode)
        await client.connect()
        try:
            link["idx"] = (await client.get_namespace_array()).index(args.namespace)
        except Exception:
            await drop(client)
            raise
        link["client"] = client

    async def drop(client) -> None:
        link["client"] = None
        try:
            await asyncio.wait_for(client.disconnect(), 1)
        except Exception:  # noqa: BLE001 - the connection is gone anyway
            client.disconnect_socket()

    def nodes(names):
        return [link["client"].get_node(ua.NodeId(n, link["idx"])) for n in names]

    def fail(text: str) -> None:
        state["errors"] += 1
        state["last"] = text

    async def scan() -> None:
        if link["client"] is None:
            await connect()
        client = link["client"]
        if inputs:
            read = await client.read_attributes(nodes(inputs))
            bad = [dv.StatusCode for dv in read if dv.StatusCode is not None and not dv.StatusCode.is_good()]
            if bad:
                fail(bad[0].name)
            else:
                state["inputs"] = [bool(dv.Value.Value) for dv in read]
        if outputs:
            values = [boolean(v) for v in state["outputs"]]
            written = await client.write_values(nodes(outputs), values, raise_on_partial_error=False)
            bad = [s for s in written if not s.is_good()]
            if bad:
                fail(bad[0].name)
        state["scans"] += 1

    async def scan_loop() -> None:
        while True:
            async with lock:
                try:
                    await scan()
                    delay = args.period_ms / 1000
                except Exception as e:  # noqa: BLE001 - a test peer reports, never dies
                    fail(describe(e))
                    if link["client"] is not None:
                        await drop(link["client"])
                    delay = 0.2  # bounded retry delay before connecting again
            await asyncio.sleep(delay)

    async def one(name: str, value=None) -> str:
        async with lock:
            if link["client"] is None:
                return "error NotConnected"
            try:
                node = nodes([name])[0]
                if value is None:
                    return "value " + bits([await node.read_value()])
                await node.write_value(boolean(value))
                return "ok"
            except Exception as e:  # noqa: BLE001
                return f"error {describe(e)}"

    task = asyncio.create_task(scan_loop())
    print("running", flush=True)
    loop = asyncio.get_running_loop()
    while True:
        line = await loop.run_in_executor(None, sys.stdin.readline)
        words = line.split()
        if not words or words[0] == "quit":
            break
        if words[0] == "outputs":
            given = words[1] if len(words) > 1 else ""
            state["outputs"] = [c == "1" for c in given.ljust(len(outputs), "0")[: len(outputs)]]
            print("ok", flush=True)
        elif words[0] == "inputs":
            print("inputs " + bits(state["inputs"]), flush=True)
        elif words[0] == "status":
            print(f"status {state['scans']} {state['errors']} {state['last'].replace(' ', '_')}", flush=True)
        elif words[0] == "write" and len(words) == 3:
            print(await one(words[1], words[2] == "1"), flush=True)
        elif words[0] == "read" and len(words) == 2:
            print(await one(words[1]), flush=True)
        else:
            print(f"error unknown command {words[0]}", flush=True)
    task.cancel()
    async with lock:
        if link["client"] is not None:
            await drop(link["client"])


if __name__ == "__main__":
    asyncio.run(main())
