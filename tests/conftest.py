import os
import tempfile

import pytest

# Compiled models go to a cache of the tests' own (private to this user; amble refuses a cache
# others may write to) so tests never depend on a stale user cache.
_uid = os.getuid() if hasattr(os, "getuid") else "user"
os.environ.setdefault("AMBLE_CACHE_DIR", os.path.join(tempfile.gettempdir(), f"amble-test-cache-{_uid}"))


@pytest.fixture(scope="session")
def compass():
    from amble.models import load

    return load("compass-gait")


@pytest.fixture(scope="module")
def compass_built():
    """The library's compass gait and its compiled kernels (its own copy per test module)."""
    from amble.backend.kernels import compiled
    from amble.models import load

    system = load("compass-gait")
    return system, compiled(system)


@pytest.fixture
def saved_figures(monkeypatch):
    """The matplotlib figures saved during a test, in order (each still written to its file)."""
    import matplotlib.pyplot as plt

    figs = []
    orig = plt.Figure.savefig

    def keep(fig, *a, **k):
        figs.append(fig)
        return orig(fig, *a, **k)

    monkeypatch.setattr(plt.Figure, "savefig", keep)
    return figs
