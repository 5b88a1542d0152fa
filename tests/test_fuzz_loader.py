"""Fuzzed loader: random and mutated documents thrown at open and replay.

The only acceptable failure is a SketchforgeError (one readable message); no other exception,
no hang (hypothesis' deadline bounds each case)."""

import copy
import json
import os
from datetime import timedelta

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tests_support import SPEC_DOC

from sketchforge.document import fileformat as ff
from sketchforge.errors import SketchforgeError

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-10**6, 10**6) | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12),
    lambda children: st.lists(children, max_size=5) | st.dictionaries(st.text(max_size=8), children, max_size=5),
    max_leaves=25,
)

KEYS = ["format", "version", "light", "journal", "snapshot", "command", "layer", "points", "params",
        "resolution", "inflation", "smoothing", "id", "name", "direction", "closed", "index", "visible",
        "pick", "band", "stroke", "children", "text"]


def paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from paths(v, prefix + (i,))


@st.composite
def mutated_documents(draw, base=None):
    doc = copy.deepcopy(base if base is not None else VALID_WITH_SNAPSHOT)
    for _ in range(draw(st.integers(1, 4))):
        all_paths = [p for p in paths(doc) if p]
        if not all_paths:
            break
        path = draw(st.sampled_from(all_paths))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        action = draw(st.sampled_from(["replace", "delete", "key", "dup"]))
        if action == "replace":
            parent[path[-1]] = draw(json_values)
        elif action == "delete":
            del parent[path[-1]]
        elif action == "key" and isinstance(parent, dict):
            parent[draw(st.sampled_from(KEYS))] = draw(json_values)
        elif action == "dup" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[path[-1]]))
    return doc


def _snapshot_doc():
    from sketchforge.plugins.testing import FanInflater, make_test_host

    d = ff.document_from_dict(SPEC_DOC, "spec", host=make_test_host(FanInflater()))
    return json.loads(ff.dumps(d))


VALID_WITH_SNAPSHOT = _snapshot_doc()
# FUZZ_EXAMPLES=3000 for a longer local run (3000 each passed before this was committed).
FUZZ = settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "150")),
    deadline=timedelta(seconds=20),
    suppress_health_check=list(HealthCheck),
)


def open_both_ways(data, host):
    for use_snapshot in (True, False):
        try:
            ff.document_from_dict(data, "fuzz.json", host=host, use_snapshot=use_snapshot)
        except SketchforgeError as exc:
            assert str(exc)  # a message, never empty


@FUZZ
@given(json_values)
def test_random_json_is_rejected_cleanly(real_host, data):
    open_both_ways(data, real_host)


@FUZZ
@given(mutated_documents())
def test_mutated_documents_fail_only_with_documented_errors(real_host, data):
    open_both_ways(data, real_host)


@FUZZ
@given(st.binary(max_size=300) | st.text(max_size=300).map(str.encode))
def test_random_bytes_on_disk(tmp_path_factory, real_host, raw):
    p = tmp_path_factory.mktemp("fuzz") / "doc.json"
    p.write_bytes(raw)
    try:
        ff.load(p, host=real_host)
    except SketchforgeError:
        pass
