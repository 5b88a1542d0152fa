"""Fixtures of the attack corpus (helpers in attack_helpers.py)."""

from __future__ import annotations

import copy
import json
import os
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from attack_helpers import SMALL_DOC, run_cli, write_doc  # noqa: E402


@pytest.fixture
def small_doc():
    return copy.deepcopy(SMALL_DOC)


@pytest.fixture(scope="session")
def saved_doc_dict(tmp_path_factory):
    """SMALL_DOC replayed by the real plugins and saved with its snapshot (a dict to mutate)."""
    folder = tmp_path_factory.mktemp("saved")
    src = write_doc(folder / "src.json", SMALL_DOC)
    res = run_cli("replay", src, "--save", folder / "saved.json")
    assert res.rc == 0, res.err
    return json.loads((folder / "saved.json").read_text())


@pytest.fixture
def saved_doc(saved_doc_dict):
    return copy.deepcopy(saved_doc_dict)


@pytest.fixture
def umask():
    """Set the process umask for a test and restore it."""
    old = os.umask(0o022)
    os.umask(old)
    yield lambda m: os.umask(m)
    os.umask(old)
