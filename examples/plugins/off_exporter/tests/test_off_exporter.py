"""The OFF exporter through the host (atomic, one-line errors), with sketchforge's fixtures."""

import numpy as np
import pytest
import sketchforge_off_exporter as plugin

from sketchforge.plugin_api import ExportError


def read_off(path):
    lines = path.read_text().split("\n")
    assert lines[0] == "OFF"
    nv, nf, _ = map(int, lines[1].split())
    V = np.array([list(map(float, l.split())) for l in lines[2 : 2 + nv]])
    F = np.array([list(map(int, l.split())) for l in lines[2 + nv : 2 + nv + nf]])
    assert np.all(F[:, 0] == 3)
    return V, F[:, 1:]


@pytest.fixture
def doc(make_sketchforge_host, make_sketchforge_document, sketchforge_fan_inflater):
    return make_sketchforge_document(make_sketchforge_host(sketchforge_fan_inflater, plugin))


def test_off_round_trips_the_mesh_exactly(doc, tmp_path):
    out = tmp_path / "model.off"
    summary = doc.host.export(out, doc=doc)
    mesh = doc.export_mesh()
    V, F = read_off(out)
    assert np.array_equal(V, mesh.V) and np.array_equal(F, mesh.F)  # 17 digits: exact
    assert summary == f"{mesh.n_vertices} vertices, {mesh.n_faces} triangles"
    assert doc.host.provider_of(doc.host.exporter_for(out)) == plugin.__name__


def test_missing_folder_is_one_line_and_nothing_is_written(doc, tmp_path):
    with pytest.raises(ExportError) as info:
        doc.host.export(tmp_path / "nope" / "model.off", doc=doc)
    assert "does not exist" in str(info.value) and "\n" not in str(info.value)
    assert list(tmp_path.iterdir()) == []
