"""A local Dask cluster serves no dashboard: another program on the dashboard's default port
(8787) is no warning of amble's."""

import socket
import warnings

import pytest

from amble.analysis.runner import open_client


def test_local_cluster_is_quiet_when_port_8787_is_taken():
    sock = socket.socket()
    try:
        sock.bind(("127.0.0.1", 8787))
        sock.listen()
    except OSError:
        sock.close()
        pytest.skip("port 8787 is not free to take for the test")
    try:
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            client, close = open_client("dask", workers=1)
            close()
        assert not [w for w in seen if "already in use" in str(w.message)]
    finally:
        sock.close()
