"""Scheduler addresses: a Dask scheduler is used; anything else is refused at once, typed."""

from __future__ import annotations

import http.server
import socket
import threading
import time

import pytest

from amble.analysis.runner import HANDSHAKE_TIMEOUT, open_client
from amble.errors import SchedulerError

# open_client imports dask.distributed first, which takes seconds on a loaded machine; the bounds
# below are on the refusal, so the import is paid here, outside the timed part.
pytest.importorskip("dask.distributed")


def _serve(handler) -> tuple[str, threading.Event]:
    """A loopback server on a free port that runs ``handler(conn)`` per connection (bounded)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(4)
    srv.settimeout(30)
    stop = threading.Event()

    def loop() -> None:
        with srv:
            while not stop.is_set():
                try:
                    conn, _ = srv.accept()
                except OSError:
                    return
                handler(conn)

    threading.Thread(target=loop, daemon=True).start()
    return f"tcp://127.0.0.1:{srv.getsockname()[1]}", stop


def _silent(conn: socket.socket) -> None:
    time.sleep(HANDSHAKE_TIMEOUT + 1)
    conn.close()


def _ssh_banner(conn: socket.socket) -> None:
    conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
    conn.close()


@pytest.mark.parametrize("handler, said", [(_silent, "no handshake"), (_ssh_banner, "not as a Dask scheduler")])
def test_a_server_that_is_not_dask_is_refused_quickly(handler, said):
    address, stop = _serve(handler)
    t0 = time.monotonic()
    with pytest.raises(SchedulerError, match=said):
        open_client(address)
    stop.set()
    assert time.monotonic() - t0 < HANDSHAKE_TIMEOUT + 3


def test_an_http_server_is_refused_quickly():
    httpd = http.server.HTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    t0 = time.monotonic()
    try:
        with pytest.raises(SchedulerError, match="no handshake"):
            open_client(f"tcp://127.0.0.1:{httpd.server_address[1]}")
    finally:
        httpd.shutdown()
    assert time.monotonic() - t0 < HANDSHAKE_TIMEOUT + 3


@pytest.mark.parametrize("address", ["", "   "])
def test_an_empty_address_is_an_error_not_a_local_cluster(address):
    with pytest.raises(SchedulerError, match="empty scheduler address"):
        open_client(address)


def test_a_real_scheduler_passes_the_check():
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        client, close = open_client(cluster.scheduler_address)
        try:
            assert client.scheduler.address == cluster.scheduler_address
        finally:
            close()
