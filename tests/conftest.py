import os
import tempfile

import pytest

# Compiled models go to a per-session cache so tests never depend on a stale user cache.
os.environ.setdefault("AMBLE_CACHE_DIR", os.path.join(tempfile.gettempdir(), "amble-test-cache"))


@pytest.fixture(scope="session")
def compass():
    from amble.models import load

    return load("compass-gait")
