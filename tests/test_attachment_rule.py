"""One attachment rule (issue 29, point 4): the document's commands (``attachment``, ``host_of``:
mirror about the host, the app's warnings) and the assembly decide which layer a junction is
glued to by the same function, so they agree on creatures nobody here drew, also after parts
were moved until their junctions run off their hosts."""

from __future__ import annotations

import numpy as np
import pytest

from sketchforge.document import fileformat as ff
from sketchforge.document.commands import attachment, host_of
from sketchforge.plugins.testing import make_test_host


@pytest.fixture(scope="module")
def host():
    return make_test_host(entry_points=True, allowlist=["inflate", "assemble"])


def _assembly_attachments(doc):
    """{part id: host id or None, or the problem} as the assemble plugin decides them."""
    from sketchforge_assemble.assemble import _sheet
    from sketchforge_assemble.attach import find_attachments

    layers = [l for l in doc.layers if l.visible and l.mesh is not None]
    names = [l.name or l.id for l in layers]
    sheets = [_sheet(None, k, names[k], l.mesh, l.closed) for k, l in enumerate(layers)]
    found, warnings, _ = find_attachments(sheets, names, on_bad_junction="free")
    out = {l.id: None for l in layers}
    for a in found:
        out[layers[a.upper].id] = layers[a.lower].id
    return out, warnings


@pytest.mark.parametrize("seed", [0, 3, 5, 8])
def test_commands_and_assembly_attach_every_part_to_the_same_layer(host, seed):
    from sketchforge_assemble.testing import random_creature

    data = random_creature(seed, resolution=0.08)
    doc = ff.document_from_dict(data, "creature", host=host, use_snapshot=False)
    rng = np.random.default_rng(seed)
    # Move some parts so that their junctions leave their hosts, partly or wholly.
    parts = [l for l in doc.layers if l.mesh is not None and len(l.mesh.junction) >= 2]
    for layer in rng.permutation(parts)[: max(1, len(parts) // 2)]:
        step = rng.uniform(-0.5, 0.5, 2)
        doc.execute({"command": "transform_layer", "layer": layer.id,
                     "matrix": [[1.0, 0.0, float(step[0])], [0.0, 1.0, float(step[1])]]})
    glued, warnings = _assembly_attachments(doc)
    problems = 0
    for layer in doc.layers:
        if layer.mesh is None:
            continue
        got, problem = attachment(doc, layer)
        assert (got.id if got is not None else None) == glued[layer.id], (seed, layer.id, problem)
        if problem is not None:
            problems += 1
            assert any(problem in w for w in warnings), (problem, warnings)
            assert host_of(doc, layer) is not None  # the layer the problem names: the one to mirror about
        elif got is not None:
            assert host_of(doc, layer) is got
    # every part the assembly leaves free is said: a problem the app names too, or a junction
    # that lies on no part
    assert problems == len([w for w in warnings if "lies on no part" not in w])
    free = [l for l in doc.layers if l.mesh is not None and len(l.mesh.junction) and not l.closed
            and glued[l.id] is None and attachment(doc, l) == (None, None)]
    assert len(warnings) - problems == len(free)


def test_a_copy_in_place_is_looked_past_by_both(host):
    # a copy duplicated in place (about to be mirrored) hangs on what its twin hangs on, and
    # both the app and the assembly say it cannot be glued on top of its twin's junction: it
    # is assembled free, with a word, until it is moved (issue 34: never the whole model)
    from sketchforge_assemble.testing import random_creature

    doc = ff.document_from_dict(random_creature(0, resolution=0.08), "creature", host=host, use_snapshot=False)
    leg = next(l for l in doc.layers if l.id.startswith("leg") or l.id.startswith("limb"))
    body = host_of(doc, leg)
    doc.execute({"command": "duplicate_layer", "layer": leg.id, "id": "twin"})  # in place, in front of the leg
    twin = doc.layer("twin")
    assert host_of(doc, twin) is body
    got, problem = attachment(doc, twin)
    assert got is None and "free part" in problem and "lies where the junction of" in problem
    assert attachment(doc, doc.layer(leg.id)) == (body, None)
    glued, warnings = _assembly_attachments(doc)
    assert glued["twin"] is None and glued[leg.id] == body.id
    assert any(problem in w for w in warnings)
