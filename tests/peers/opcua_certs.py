"""The OPC UA test peers' application certificates (tests/peers/opcua_plant.py and
opcua_plc.py): self-signed, with the application URI and the local host names."""

import ipaddress
import socket
from pathlib import Path

from asyncua.crypto.cert_gen import dump_private_key_as_pem, generate_private_key, generate_self_signed_app_certificate
from cryptography import x509
from cryptography.hazmat.primitives.serialization import Encoding


def ensure_certificate(cert: Path, key: Path, uri: str, use: x509.ObjectIdentifier) -> None:
    """A self-signed application certificate (DER) and key (PEM), made once."""
    if cert.is_file() and key.is_file():
        return
    cert.parent.mkdir(parents=True, exist_ok=True)
    pkey = generate_private_key()
    names = [
        x509.UniformResourceIdentifier(uri),
        x509.DNSName("localhost"),
        x509.DNSName(socket.gethostname()),
        x509.IPAddress(ipaddress.ip_address("127.0.0.1")),
    ]
    made = generate_self_signed_app_certificate(pkey, uri, {}, names, [use], days=3650)
    key.write_bytes(dump_private_key_as_pem(pkey))
    cert.write_bytes(made.public_bytes(Encoding.DER))
