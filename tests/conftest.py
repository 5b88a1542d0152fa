import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

# Qt (when a test imports it) must never need a display unless the test is a GL test.
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
# Autosaves and app settings written by tests never touch the user's own folders.
_DATA_DIR = tempfile.mkdtemp(prefix="sketchforge-test-data-")
os.environ["SKETCHFORGE_DATA_DIR"] = _DATA_DIR
atexit.register(shutil.rmtree, _DATA_DIR, ignore_errors=True)
sys.path.insert(0, str(Path(__file__).parent))

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def fan_host():
    """Core commands + a fast fake inflater (document-machinery tests)."""
    from sketchforge.plugins.testing import FanInflater, make_test_host

    return make_test_host(FanInflater())


@pytest.fixture(scope="session")
def real_host():
    """Every installed plugin (the real inflate, sculpt and assemble plugins)."""
    from sketchforge.plugins.manager import default_host

    return default_host()


@pytest.fixture
def examples_dir():
    return ROOT / "examples"


@pytest.fixture(scope="session")
def dask_engine():
    """A real local Dask cluster of one worker process, shared by the batch and dataset tests
    (starting one costs a few seconds)."""
    from sketchforge.batch.engine import Engine

    with Engine(workers=1) as engine:
        yield engine
