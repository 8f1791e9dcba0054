"""Channel targets and the service config."""

from __future__ import annotations

import ipaddress
import json
import pathlib
from typing import Sequence, Union

_SERVICE_CONFIG = pathlib.Path(__file__).with_name("service_config.json")


def service_config_json() -> str:
    """client/service_config.json (copied here at build time): round_robin and the retry policy
    for UNAVAILABLE."""
    return json.dumps(json.loads(_SERVICE_CONFIG.read_text()))


def _host(address: str) -> str:
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit():
        raise ValueError(f"target {address!r}: expected HOST:PORT")
    return host[1:-1] if host.startswith("[") and host.endswith("]") else host


def _parts(target: Union[str, Sequence[str]]) -> list:
    parts = list(target.split(",") if isinstance(target, str) else target)
    if not parts or any(not p for p in parts):
        raise ValueError(f"target {target!r}: an empty address")
    return parts


def target_of_one(target: Union[str, Sequence[str]]) -> str:
    """The target itself when it names one server, else ""."""
    parts = _parts(target)
    return parts[0] if len(parts) == 1 else ""


def first_host(target: Union[str, Sequence[str]]) -> str:
    """The host of the first target: the name TLS checks when several replicas are dialled."""
    return _host(_parts(target)[0])


def channel_target(target: Union[str, Sequence[str]]) -> str:
    """One target is passed to gRPC as it is ("HOST:PORT", "dns:///NAME:PORT", ...). Several
    (a list, or one string with commas) must be IP literals of one family, "ipv4:A,B,C" for gRPC;
    for host names use one DNS name that resolves to every replica."""
    parts = _parts(target)
    if len(parts) == 1:
        return parts[0]
    families = set()
    for p in parts:
        try:
            families.add(ipaddress.ip_address(_host(p)).version)
        except ValueError:
            raise ValueError(
                f"target {p!r}: several targets must be IP:PORT literals; for host names use one "
                "DNS name (dns:///NAME:PORT) that resolves to every replica") from None
    if len(families) != 1:
        raise ValueError(f"server {target!r}: mixes IPv4 and IPv6")
    return ("ipv4:" if families == {4} else "ipv6:") + ",".join(parts)
