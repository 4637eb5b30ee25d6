r"""The address of an existing Dask scheduler (``--scheduler``), checked before Dask is asked
to connect to it: its syntax and protocol, then one plain TCP connection that must receive a
Dask handshake within the connect timeout.

Only ``tcp://HOST:PORT`` is taken (``HOST`` a name, an IPv4 address or ``[IPv6]``, ``PORT``
1..65535).  ``tls://`` and ``wss://`` need a security configuration (certificates) that
``substruct study`` does not take; ``ucx://``, ``ws://``, ``inproc://`` and any other protocol
are refused.  Each refusal is a :class:`BackendError` of one line.

A Dask server writes its handshake as soon as a connection is accepted: an 8-byte frame length
:math:`N`, then :math:`N` bytes that start with the number of frames :math:`k` and their
:math:`k` lengths (8 bytes each), which add up to the rest,

.. math::  8\,(1 + k) + \sum_{i=1}^{k} n_i = N, \qquad 8\,(1 + k) \le N \le N_{max} .

:func:`probe` reads exactly that and nothing more, so that a closed port fails at once, a
server that never answers fails after the timeout, and a server that speaks another protocol
(a web server, which waits for a request; an SSH server, whose banner is not a frame length)
is refused without Dask reading its bytes as a frame length (``HTTP/1.0`` read as a length is
3.07 EiB).
"""

from __future__ import annotations

import ipaddress
import math
import re
import socket
import struct
import time

from substruct.case.errors import printable

__all__ = ["BackendError", "SchedulerAddress", "scheduler_address", "connect_timeout", "probe",
           "MAX_HANDSHAKE", "MAX_CONNECT_TIMEOUT"]

#: The largest handshake accepted from a scheduler (bytes; Dask's is under 100).
MAX_HANDSHAKE = 65536
#: The longest ``--connect-timeout`` (seconds).
MAX_CONNECT_TIMEOUT = 300.0
#: A host name: labels of letters, digits and hyphens, separated by dots.
_HOST = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9-]{0,62})(?:\.[A-Za-z0-9-]{1,63})*\.?")
_FRAME = struct.Struct("Q")  # what distributed.comm.tcp reads: native unsigned 64 bits


class BackendError(RuntimeError):
    """The backend cannot be used: Dask not installed, the scheduler not reachable or not a
    scheduler, the address or its protocol refused."""


class SchedulerAddress(str):
    """A checked ``tcp://host:port`` (a ``str``), with its ``host`` and ``port``."""

    host: str
    port: int


def _shown(text: str) -> str:
    """``text`` quoted, its control and format characters escaped (``repr``), shortened."""
    return repr(text if len(text) <= 80 else text[:77] + "...")


def scheduler_address(text: str) -> SchedulerAddress:
    """``text`` checked as ``tcp://HOST:PORT``.

    Raises:
        BackendError: another protocol, no port, a host or port that cannot be one; the line
            names ``--scheduler`` and shows the value.
    """
    scheme, sep, rest = text.partition("://")
    if not sep:
        raise BackendError(f"--scheduler: an address such as tcp://SCHEDULER_HOST:8786, got "
                           f"{_shown(text)}")
    scheme = scheme.lower()
    if scheme in ("tls", "wss"):
        raise BackendError(f"--scheduler: {scheme}:// needs a TLS security configuration "
                           f"(certificates) that substruct study does not take; reach the "
                           f"scheduler over tcp:// (for instance through an SSH tunnel), got "
                           f"{_shown(text)}")
    if scheme != "tcp":
        raise BackendError(f"--scheduler: protocol {printable(scheme)[:20]}:// is not "
                           f"supported (only tcp://HOST:PORT), got {_shown(text)}")
    host, colon, port = rest.rpartition(":")
    if not colon or not port:
        raise BackendError(f"--scheduler: give the port, as in tcp://SCHEDULER_HOST:8786, got "
                           f"{_shown(text)}")
    if host.startswith("[") and host.endswith("]"):
        try:
            ipaddress.IPv6Address(host[1:-1])
        except ValueError:
            raise BackendError(f"--scheduler: not an IPv6 address in brackets, got "
                               f"{_shown(text)}") from None
        name = host[1:-1]
    elif len(host) <= 253 and _HOST.fullmatch(host):
        name = host
    else:
        raise BackendError(f"--scheduler: not a host name or IP address, got {_shown(text)}")
    if not (port.isascii() and port.isdigit() and len(port) <= 5 and 1 <= int(port) <= 65535):
        raise BackendError(f"--scheduler: the port is a number in 1..65535, got "
                           f"{_shown(text)}")
    out = SchedulerAddress(f"tcp://{host}:{int(port)}")
    out.host, out.port = name, int(port)
    return out


def connect_timeout(seconds: float) -> float:
    """``seconds`` checked as a connect timeout: finite, above 0, at most
    :data:`MAX_CONNECT_TIMEOUT`.

    Raises:
        BackendError: otherwise, naming ``--connect-timeout``.
    """
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_CONNECT_TIMEOUT):
        raise BackendError(f"--connect-timeout: seconds above 0 and at most "
                           f"{MAX_CONNECT_TIMEOUT:g}, got {seconds!r}")
    return float(seconds)


def _read(sock: socket.socket, n: int, deadline: float) -> bytes:
    """Exactly ``n`` bytes, or fewer if the peer closed; ``TimeoutError`` at ``deadline``."""
    data = b""
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError
        sock.settimeout(left)
        chunk = sock.recv(n - len(data))
        if not chunk:
            break
        data += chunk
    return data


def _frames_ok(body: bytes) -> bool:
    """The frame header of a handshake body: ``k`` then ``k`` lengths that add up."""
    if len(body) < _FRAME.size:
        return False
    (k,) = _FRAME.unpack_from(body)
    if not 1 <= k <= (len(body) - _FRAME.size) // _FRAME.size:
        return False
    lengths = [_FRAME.unpack_from(body, _FRAME.size * (1 + i))[0] for i in range(k)]
    return _FRAME.size * (1 + k) + sum(lengths) == len(body)


def probe(address: SchedulerAddress, timeout: float) -> None:
    """One TCP connection to ``address`` that must receive a Dask handshake within
    ``timeout`` seconds (then closed; nothing is sent).

    Raises:
        BackendError: nothing listens there (at once), no answer or no handshake within the
            timeout, the peer closed the connection, or what it sent is not a handshake.
    """
    where = f"--scheduler {address}"
    deadline = time.monotonic() + timeout
    try:
        sock = socket.create_connection((address.host, address.port), timeout=timeout)
    except ConnectionRefusedError:
        raise BackendError(f"{where}: nothing listens there (connection refused)") from None
    except socket.gaierror as err:
        raise BackendError(f"{where}: cannot resolve {printable(address.host)} "
                           f"({printable(str(err.strerror or err))})") from None
    except TimeoutError:
        raise BackendError(f"{where}: no connection within {timeout:g} s "
                           f"(--connect-timeout)") from None
    except OSError as err:
        raise BackendError(f"{where}: cannot connect "
                           f"({printable(err.strerror or type(err).__name__)})") from None
    with sock:
        try:
            head = _read(sock, _FRAME.size, deadline)
            if len(head) < _FRAME.size:
                raise BackendError(f"{where}: not a Dask scheduler (it closed the connection "
                                   f"without a Dask handshake)")
            (n,) = _FRAME.unpack(head)
            if not 2 * _FRAME.size <= n <= MAX_HANDSHAKE:
                raise BackendError(f"{where}: not a Dask scheduler (its first bytes "
                                   f"{printable(repr(head))} are not a Dask handshake)")
            body = _read(sock, n, deadline)
        except TimeoutError:
            raise BackendError(f"{where}: not a Dask scheduler (no Dask handshake within "
                               f"{timeout:g} s, --connect-timeout)") from None
        except OSError as err:
            raise BackendError(f"{where}: the connection failed before a Dask handshake "
                               f"({printable(err.strerror or type(err).__name__)})") from None
    if len(body) < n or not _frames_ok(body):
        raise BackendError(f"{where}: not a Dask scheduler (a malformed Dask handshake)")
