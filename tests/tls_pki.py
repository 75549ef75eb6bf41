"""Certificates for TLS tests, made with the ``openssl`` command as docs/hosts.md makes them, and the
Zenoh configuration files that use them.

`make_pki` writes a certificate authority and certificates it signs for ``world``, ``agent`` and
``viewer`` (each its own common name, with the subject alternative names 127.0.0.1 and localhost),
and a ``rogue`` certificate signed by another authority.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

#: The certificates `make_pki` writes, each with the authority that signs it.
SIGNED_BY = {"world": "ca", "agent": "ca", "viewer": "ca", "rogue": "other-ca"}

_EXTENSIONS = "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth,clientAuth\n"


def _openssl(*words: str) -> None:
    subprocess.run(["openssl", *words], check=True, capture_output=True)


def make_pki(folder: Path) -> Path:
    """Write ``ca.pem``, ``other-ca.pem`` and ``<name>.pem`` / ``<name>.key`` for each of `SIGNED_BY`.

    Args:
        folder: where the files go.

    Returns:
        ``folder``.
    """
    folder.mkdir(parents=True, exist_ok=True)
    for ca in ("ca", "other-ca"):
        _openssl("req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
                 "-keyout", str(folder / f"{ca}.key"), "-subj", f"/CN=homebot test {ca}", "-days", "2",
                 "-out", str(folder / f"{ca}.pem"))
    (folder / "peer.ext").write_text(_EXTENSIONS)
    for name, ca in SIGNED_BY.items():
        _openssl("req", "-new", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
                 "-keyout", str(folder / f"{name}.key"), "-subj", f"/CN={name}", "-out", str(folder / f"{name}.csr"))
        _openssl("x509", "-req", "-in", str(folder / f"{name}.csr"), "-CA", str(folder / f"{ca}.pem"),
                 "-CAkey", str(folder / f"{ca}.key"), "-CAcreateserial", "-days", "2",
                 "-extfile", str(folder / "peer.ext"), "-out", str(folder / f"{name}.pem"))
    return folder


def zenoh_file(pki: Path, name: str, cert: str | None, access_control: dict[str, Any] | None = None) -> Path:
    """A Zenoh configuration file trusting ``ca.pem``, with mutual TLS and ``cert``'s certificate
    for both listening and connecting (none when ``cert`` is None), and the access control given.

    Args:
        pki: the folder of `make_pki`.
        name: the file's name, without extension.
        cert: the certificate's name (``agent``…), or None.
        access_control: the ``access_control`` section, or None.

    Returns:
        The file, ``<pki>/<name>.json5``.
    """
    tls: dict[str, Any] = {"root_ca_certificate": str(pki / "ca.pem"), "enable_mtls": True}
    if cert is not None:
        for side in ("listen", "connect"):
            tls[f"{side}_certificate"] = str(pki / f"{cert}.pem")
            tls[f"{side}_private_key"] = str(pki / f"{cert}.key")
    config: dict[str, Any] = {"transport": {"link": {"tls": tls}}}
    if access_control is not None:
        config["access_control"] = access_control
    path = pki / f"{name}.json5"
    path.write_text("// written by tests/tls_pki.py\n" + json.dumps(config, indent=2))
    return path


def world_access(namespace: str) -> dict[str, Any]:
    """Access control for a world under ``namespace``: the ``agent`` certificate may do everything
    under it; the ``viewer`` certificate may only ask for the robot's description and see that the
    world is alive; anything else is denied.

    Args:
        namespace: the world's namespace.

    Returns:
        The ``access_control`` section.
    """
    queries = ["query", "reply", "declare_queryable"]
    liveliness = ["liveliness_token", "declare_liveliness_subscriber", "liveliness_query"]
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": [
            {"id": "everything", "permission": "allow", "flows": ["ingress", "egress"],
             "messages": [*queries, *liveliness, "put", "delete", "declare_subscriber"],
             "key_exprs": [f"{namespace}/**", "homebot/agents/**"]},
            {"id": "description only", "permission": "allow", "flows": ["ingress", "egress"],
             "messages": [*queries, *liveliness],
             "key_exprs": [f"{namespace}/world/robot/description", f"{namespace}/world/alive"]},
        ],
        "subjects": [{"id": "agents", "cert_common_names": ["agent"]},
                     {"id": "viewers", "cert_common_names": ["viewer"]}],
        "policies": [{"rules": ["everything"], "subjects": ["agents"]},
                     {"rules": ["description only"], "subjects": ["viewers"]}],
    }
