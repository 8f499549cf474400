"""A plant for Vigie's integration tests: an asyncua OPC UA server on 127.0.0.1.

A folder `Plant` under Objects holds one writable Boolean variable per signal named by
`--inputs` (sensors) and `--outputs` (actuators), node id `ns=<idx>;s=<name>` in the
namespace `--namespace`; the script knows nothing else of the plant. `--mirror A:D,...`
wires mirror contacts: a client write to output A sets input D in the same request.
`--security none|sign|encrypt|all` (Basic256Sha256) with `--cert-dir` (own certificate
server_cert.der + server_key.pem, made if absent), `--trust DIR` (files of DER client
certificates; any other client certificate is refused, reread at each session) and
`--user NAME:PASSWORD` (then anonymous is refused). Driven line by line on stdin:
  set NAME 0|1 [NAME 0|1 ...]   set signals, all in one step   -> "ok"
  outputs                       the outputs, in --outputs order -> "outputs 0100..."
  inputs                        the inputs, in --inputs order   -> "inputs 0100..."
  quit                          stop
Prints "listening PORT" once serving on opc.tcp://127.0.0.1:PORT/. `--port N` reuses a
port (restart after a kill).
"""

import argparse
import asyncio
import contextlib
import logging
import socket
import sys
from pathlib import Path

from asyncua import Server, ua
from asyncua.common.callback import CallbackType
from asyncua.common.utils import ServiceError
from asyncua.crypto.permission_rules import User, UserRole
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding
from cryptography.x509.oid import ExtendedKeyUsageOID
from opcua_certs import ensure_certificate

APP_URI = "urn:vigie:test:plant"
POLICIES = {
    "none": [ua.SecurityPolicyType.NoSecurity],
    "sign": [ua.SecurityPolicyType.Basic256Sha256_Sign],
    "encrypt": [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt],
    "all": [
        ua.SecurityPolicyType.NoSecurity,
        ua.SecurityPolicyType.Basic256Sha256_Sign,
        ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt,
    ],
}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class OneUser:
    """Accepts exactly one user name and password, nothing else."""

    def __init__(self, name: str, password: str):
        self.name, self.password = name, password

    def get_user(self, iserver, username=None, password=None, certificate=None):
        if username == self.name and password == self.password:
            return User(role=UserRole.User, name=username)
        return None


def trust_validator(folder: Path):
    async def validate(cert: x509.Certificate, _app: ua.ApplicationDescription) -> None:
        trusted = {p.read_bytes() for p in folder.iterdir() if p.is_file()}
        if cert.public_bytes(Encoding.DER) not in trusted:
            raise ServiceError(ua.StatusCodes.BadCertificateUntrusted)

    return validate


def bits(values) -> str:
    return "".join("1" if v else "0" for v in values)


async def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--port", type=int, default=0)
    parser.add_argument("--namespace", required=True)
    parser.add_argument("--inputs", default="", help="C0,C1,... sensor names")
    parser.add_argument("--outputs", default="", help="A0,A1,... actuator names")
    parser.add_argument("--mirror", default="", help="A:D,... output A mirrored on input D")
    parser.add_argument("--security", choices=sorted(POLICIES), default="none")
    parser.add_argument("--cert-dir", type=Path)
    parser.add_argument("--trust", type=Path)
    parser.add_argument("--user", default=None, help="NAME:PASSWORD, the only identity accepted")
    args = parser.parse_args()
    if args.security != "none" and args.cert_dir is None:
        parser.error("--security other than none needs --cert-dir")
    inputs = [n for n in args.inputs.split(",") if n]
    outputs = [n for n in args.outputs.split(",") if n]
    wiring = dict(p.split(":") for p in args.mirror.split(",") if p)
    if not set(sum(wiring.items(), ())) <= set(inputs + outputs):
        parser.error("--mirror names a signal not in --inputs/--outputs")
    logging.disable(logging.CRITICAL)  # rejected clients log ERRORs: keep stderr empty
    port = args.port or free_port()

    user_manager = OneUser(*args.user.split(":", 1)) if args.user else None
    server = Server(user_manager=user_manager)
    await server.init()
    server.set_endpoint(f"opc.tcp://127.0.0.1:{port}/")
    server.set_server_name("Vigie test plant")
    await server.set_application_uri(APP_URI)
    server.set_security_policy(POLICIES[args.security])
    if args.user:
        server.set_identity_tokens([ua.UserNameIdentityToken])
    if args.cert_dir is not None:
        cert, key = args.cert_dir / "server_cert.der", args.cert_dir / "server_key.pem"
        ensure_certificate(cert, key, APP_URI, ExtendedKeyUsageOID.SERVER_AUTH)
        await server.load_certificate(cert)
        await server.load_private_key(key)
    if args.trust is not None:
        server.set_certificate_validator(trust_validator(args.trust))

    idx = await server.register_namespace(args.namespace)
    folder = await server.nodes.objects.add_folder(idx, "Plant")
    ids = {}
    for name in inputs + outputs:
        var = await folder.add_variable(ua.NodeId(name, idx), ua.QualifiedName(name, idx), False, ua.VariantType.Boolean)
        await var.set_writable()
        ids[name] = var.nodeid
    mirrors = {ids[a]: ids[d] for a, d in wiring.items()}

    async def write(nodeid: ua.NodeId, value: bool) -> None:
        await server.write_attribute_value(nodeid, ua.DataValue(ua.Variant(value, ua.VariantType.Boolean)))

    async def mirror(event, _dispatcher) -> None:
        # Runs before the Write response is sent: the mirror is set in the same request.
        for wv, status in zip(event.request_params.NodesToWrite, event.response_params):
            d = mirrors.get(wv.NodeId)
            if d is not None and status.is_good() and wv.AttributeId == ua.AttributeIds.Value:
                await write(d, bool(wv.Value.Value.Value))

    server.subscribe_server_callback(CallbackType.PostWrite, mirror)

    def read(names) -> str:
        return bits(server.read_attribute_value(ids[n]).Value.Value for n in names)

    await server.start()
    print(f"listening {port}", flush=True)
    loop = asyncio.get_running_loop()
    while True:
        line = await loop.run_in_executor(None, sys.stdin.readline)
        words = line.split()
        if not words or words[0] == "quit":
            break
        if words[0] == "set":
            pairs = list(zip(words[1::2], words[2::2]))
            unknown = [n for n, _ in pairs if n not in ids]
            if unknown:
                print(f"error unknown {unknown[0]}", flush=True)
                continue
            for n, v in pairs:
                await write(ids[n], v == "1")
            print("ok", flush=True)
        elif words[0] == "outputs":
            print("outputs " + read(outputs), flush=True)
        elif words[0] == "inputs":
            print("inputs " + read(inputs), flush=True)
        else:
            print(f"error unknown command {words[0]}", flush=True)
    with contextlib.suppress(Exception):  # stopping anyway
        await asyncio.wait_for(server.stop(), 2)


if __name__ == "__main__":
    asyncio.run(main())
