"""``substruct study --scheduler``: the address and protocol checked before anything is sent,
then a Dask handshake required within ``--connect-timeout``; every failure one line, exit 2,
nothing written.  The servers are fakes started here on 127.0.0.1 (threads of this process):
one that closes each connection, one that never answers, a web server, a server that sends a
banner, and one that sends a Dask handshake and then answers like a web server."""

from __future__ import annotations

import os
import socket
import struct
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from substruct import cli
from substruct.studies.scheduler_probe import (
    BackendError,
    MAX_HANDSHAKE,
    probe,
    scheduler_address,
)

ROOT = Path(__file__).resolve().parent.parent
TUNING = ROOT / "cases" / "tapered_rod_tuning.yaml"
HTTP = b"HTTP/1.0 400 Bad Request\r\nContent-Type: text/html\r\nContent-Length: 0\r\n\r\n"
#: What a Dask scheduler sends first (distributed 2026.8, read off a real one): the frames'
#: length, one frame of 42 bytes, a msgpack map.
BODY = b"\x83\xabcompression\xc0\xa6python\x93\x03\x0b\x07\xafpickle-protocol\x05"
HANDSHAKE = struct.pack("QQQ", 16 + len(BODY), 1, len(BODY)) + BODY


class FakeServer:
    """A TCP server on 127.0.0.1 in a thread; ``behaviour(connection)`` per connection; stopped
    (and every connection closed) by :meth:`stop`."""

    def __init__(self, behaviour):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.port = self.sock.getsockname()[1]
        self.behaviour = behaviour
        self.connections: list[socket.socket] = []
        self.stopped = threading.Event()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self):
        while not self.stopped.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.connections.append(conn)
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn):
        try:
            self.behaviour(conn, self.stopped)
        except OSError:
            pass

    @property
    def address(self) -> str:
        return f"tcp://127.0.0.1:{self.port}"

    def stop(self):
        self.stopped.set()
        self.sock.close()
        for c in self.connections:
            c.close()


def closes(conn, stopped):
    conn.close()


def never_answers(conn, stopped):
    stopped.wait(60)


def web_server(conn, stopped):
    """Waits for a request, answers 400 (a web server's answer to Dask's handshake)."""
    conn.settimeout(60)
    if conn.recv(65536):
        conn.sendall(HTTP)
    conn.close()


def banner(conn, stopped):
    conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
    stopped.wait(60)


def dask_then_web(conn, stopped):
    """A Dask handshake, then a web server's answer to whatever comes."""
    conn.sendall(HANDSHAKE)
    conn.settimeout(60)
    while conn.recv(65536):
        conn.sendall(HTTP)


@pytest.fixture
def server(request):
    s = FakeServer(request.param)
    yield s
    s.stop()


def study(tmp_path, *more):
    """``substruct study`` of the shipped tuning study, in this process: (exit code, stderr,
    seconds)."""
    out = tmp_path / "out"
    start = time.monotonic()
    code = cli.main(["study", str(TUNING), "--out", str(out), "--no-pictures", *more])
    return code, time.monotonic() - start


def assert_one_line(capsys, fragment, tmp_path):
    captured = capsys.readouterr()
    err = captured.err
    assert captured.out == ""
    assert err.count("\n") == 1 and err.startswith("substruct: error: "), err
    assert fragment in err, err
    assert "Traceback" not in err and "internal error" not in err
    out = tmp_path / "out"
    assert not out.exists() or not any(out.iterdir())
    return err


# ----------------------------------------------------------------- the address


@pytest.mark.parametrize("address, fragment", [
    ("tls://127.0.0.1:8786", "tls:// needs a TLS security configuration"),
    ("wss://127.0.0.1:8786", "wss:// needs a TLS security configuration"),
    ("ucx://127.0.0.1:8786", "protocol ucx:// is not supported (only tcp://HOST:PORT)"),
    ("ws://127.0.0.1:8786", "protocol ws:// is not supported"),
    ("inproc://127.0.0.1/1/2", "protocol inproc:// is not supported"),
    ("127.0.0.1:8786", "an address such as tcp://SCHEDULER_HOST:8786, got '127.0.0.1:8786'"),
    ("tcp://127.0.0.1", "give the port"),
    ("tcp://127.0.0.1:", "give the port"),
    ("tcp://127.0.0.1:0", "the port is a number in 1..65535"),
    ("tcp://127.0.0.1:65536", "the port is a number in 1..65535"),
    ("tcp://127.0.0.1:8786/path", "the port is a number in 1..65535"),
    ("tcp://127.0.0.1:٨٧٨٦", "the port is a number in 1..65535"),
    ("tcp://a b:8786", "not a host name or IP address"),
    ("tcp://[zz::1]:8786", "not an IPv6 address in brackets"),
    ("tcp://x\x1b]0;owned\x07:8786", "not a host name or IP address, got 'tcp://x\\x1b]0;owned"),
    ("tcp://" + "a" * 300 + ":8786", "not a host name or IP address"),
])
def test_an_address_is_refused_before_anything_is_sent(address, fragment, tmp_path, capsys):
    code, _ = study(tmp_path, "--scheduler", address)
    assert code == 2
    err = assert_one_line(capsys, fragment, tmp_path)
    assert "\x1b" not in err and "\x07" not in err


@pytest.mark.parametrize("text, host, port", [
    ("tcp://127.0.0.1:8786", "127.0.0.1", 8786),
    ("tcp://[::1]:8786", "::1", 8786),
    ("TCP://scheduler-1.example:00042", "scheduler-1.example", 42),
])
def test_an_address_that_is_taken(text, host, port):
    address = scheduler_address(text)
    assert (address.host, address.port) == (host, port)
    assert address.startswith("tcp://") and address.endswith(f":{port}")


@pytest.mark.parametrize("seconds", ["nan", "inf", "0", "-1", "301"])
def test_a_connect_timeout_out_of_range_is_one_line(seconds, tmp_path, capsys):
    code, _ = study(tmp_path, "--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", seconds)
    assert code == 2
    assert_one_line(capsys, "--connect-timeout: seconds above 0 and at most 300", tmp_path)


def test_a_connect_timeout_without_a_scheduler_is_refused(tmp_path, capsys):
    code, _ = study(tmp_path, "--workers", "2", "--connect-timeout", "3")
    assert code == 2
    assert_one_line(capsys, "--connect-timeout: only with --scheduler, got 3.0", tmp_path)


# ----------------------------------------------------------------- fake servers


def closed_port() -> int:
    """A port of 127.0.0.1 nothing listens on (bound, then released; not listening)."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_a_closed_port_fails_at_once_not_after_the_timeout(tmp_path, capsys):
    code, seconds = study(tmp_path, "--scheduler", f"tcp://127.0.0.1:{closed_port()}",
                          "--connect-timeout", "60")
    assert code == 2
    assert_one_line(capsys, "nothing listens there (connection refused)", tmp_path)
    assert seconds < 20  # the timeout (60 s) is not waited for; it used to be 20 s


@pytest.mark.parametrize("server, fragment", [
    (closes, "not a Dask scheduler (it closed the connection without a Dask handshake)"),
    (never_answers, "not a Dask scheduler (no Dask handshake within 1.5 s, --connect-timeout)"),
    (web_server, "not a Dask scheduler (no Dask handshake within 1.5 s, --connect-timeout)"),
    (banner, "not a Dask scheduler (its first bytes b'SSH-2.0-' are not a Dask handshake)"),
], indirect=["server"], ids=["closes", "never-answers", "web-server", "ssh-banner"])
def test_a_server_that_is_not_a_scheduler_is_one_line_exit_2(server, fragment, tmp_path,
                                                              capsys):
    code, seconds = study(tmp_path, "--scheduler", server.address, "--connect-timeout", "1.5")
    assert code == 2
    assert_one_line(capsys, f"--scheduler {server.address}: {fragment}", tmp_path)
    assert seconds < 1.5 + 20  # bounded by the timeout (generous for a loaded machine)
    if "within" in fragment:
        assert seconds >= 1.5


@pytest.mark.parametrize("server", [never_answers], indirect=True)
def test_the_timeout_is_the_one_given(server):
    """The probe waits for the handshake ``timeout`` seconds, not Dask's 30 s default."""
    address = scheduler_address(server.address)
    for timeout in (0.3, 1.2):
        start = time.monotonic()
        with pytest.raises(BackendError, match=f"no Dask handshake within {timeout:g} s"):
            probe(address, timeout)
        assert timeout <= time.monotonic() - start < timeout + 5


def test_the_probe_takes_a_dask_handshake_and_refuses_a_lying_one():
    """The handshake format is the one a real scheduler sends (the test of ``--scheduler``
    against ``dask scheduler`` in tests/test_study.py goes through the same probe)."""
    def sends(data):
        def behaviour(conn, stopped):
            conn.sendall(data)
            stopped.wait(60)
        return behaviour

    cases = [
        (HANDSHAKE, None),
        (struct.pack("Q", MAX_HANDSHAKE + 1) + b"x" * 64, "are not a Dask handshake"),
        (struct.pack("QQQ", 16 + len(BODY), 2, len(BODY)) + BODY, "a malformed Dask handshake"),
        (struct.pack("QQQ", 16 + len(BODY), 1, len(BODY) + 1) + BODY,
         "a malformed Dask handshake"),
        (struct.pack("Q", 64) + b"x" * 10, "no Dask handshake within 0.5 s"),  # too short
    ]
    for data, fragment in cases:
        s = FakeServer(sends(data))
        try:
            if fragment is None:
                probe(scheduler_address(s.address), 0.5)
            else:
                with pytest.raises(BackendError, match=fragment):
                    probe(scheduler_address(s.address), 0.5)
        finally:
            s.stop()


@pytest.mark.parametrize("server", [dask_then_web], indirect=True)
def test_a_handshake_then_a_web_server_is_one_line_not_a_memory_error(server, tmp_path):
    """Past the probe, Dask reads the web server's ``HTTP/1.0`` as a frame length (3 EiB): the
    MemoryError is contained in the one line, and the half-made client is closed (no
    'Exception ignored' at exit).  In a subprocess: Dask's threads stay out of pytest."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg", "OMP_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-m", "substruct.cli", "study", str(TUNING),
                           "--out", str(tmp_path / "out"), "--scheduler", server.address,
                           "--connect-timeout", "3"], capture_output=True, text=True,
                          env=env, timeout=120, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert done.stderr.count("\n") == 1, done.stderr
    assert done.stderr.startswith(f"substruct: error: --scheduler {server.address}: not a Dask "
                                  f"scheduler (the connection failed: ")
    assert "internal error" not in done.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_no_test_address_leaves_loopback():
    """Every address of the docs and tests is loopback or the SCHEDULER_HOST placeholder."""
    import re

    private = re.compile(r"\b(10\.\d+|172\.(1[6-9]|2\d|3[01])|192\.168)\.\d+\.\d+\b")
    files = [*ROOT.glob("docs/*.md"), ROOT / "README.md", *ROOT.glob("tests/*.py"),
             *ROOT.glob("examples/**/*"), *ROOT.glob("cases/*.yaml")]
    hits = [f"{p.relative_to(ROOT)}: {m.group(0)}" for p in files if p.is_file()
            for m in private.finditer(p.read_text(errors="replace"))]
    assert hits == []
