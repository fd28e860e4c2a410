"""Shared test setup: the project root (for tangle.py) and the shared data beside the project; the
rule for warnings made errors inside a test (`warnings_as_errors`)."""
import contextlib
import sys
import warnings
from pathlib import Path

import pytest

PROJECT_ROOT = Path(__file__).resolve().parents[1]
SHARED = PROJECT_ROOT.parent / "shared"
if str(PROJECT_ROOT) not in sys.path:
    sys.path.insert(0, str(PROJECT_ROOT))

# Where a deprecation warning comes from: the module it is attributed to (the frame that called the
# deprecated thing). One raised by numpy about python-control's code is control's to mend, not ours;
# one attributed to a module of ident is ours, and fails.
DEPENDENCIES = ("control", "scipy", "numpy", "matplotlib", "pandas", "dask", "distributed", "jupytext",
                "nbformat", "threadpoolctl", "nfoursid", "hypothesis", "PIL", "pygments", "markdown_it",
                "mdit_py_plugins", "latex2mathml")
DEPENDENCY_MODULES = r"(" + "|".join(DEPENDENCIES) + r")(\.|$)"


def ignore_dependency_deprecations() -> None:
    """In the current warnings context: deprecation warnings attributed to a dependency's modules are
    ignored (they are not ours to mend; a newer numpy or scipy may add them at any release)."""
    for category in (DeprecationWarning, PendingDeprecationWarning):
        warnings.filterwarnings("ignore", category=category, module=DEPENDENCY_MODULES)


@contextlib.contextmanager
def warnings_as_errors(category=Warning):
    """Every warning of `category` an error, except a dependency's deprecation warnings."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", category)
        ignore_dependency_deprecations()
        yield


@contextlib.contextmanager
def recorded_warnings():
    """The warnings raised inside, every one recorded (the list is yielded), a dependency's deprecation
    warnings left out."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ignore_dependency_deprecations()
        yield caught


@pytest.fixture
def project_root() -> Path:
    return PROJECT_ROOT


@contextlib.contextmanager
def local_http_server(handler):
    """An HTTP server on a free local port, serving with `handler` in a thread: yields the port."""
    import http.server
    import threading

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.timeout = 5
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    try:
        yield server.server_address[1]
    finally:
        server.shutdown()
        server.server_close()
        thread.join(timeout=5)
