"""``sketchforge dataset``: random shape-from-shading samples made on the batch engine (a real
local Dask cluster), each consistent in itself (shading = max(0, R(n, l)), depth's slopes =
the normals'), reproduced by its document, and the same bytes for the same seed."""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from sketchforge import cli
from sketchforge.batch import samples
from sketchforge.batch.dataset import (
    MANIFEST_NAME,
    dataset_sample,
    manifest_bytes,
    prepare_dataset_dir,
    render_sample,
    run_dataset,
)
from sketchforge.batch.jobs import software
from sketchforge.batch.progress import ProgressBar

SEED, COUNT, SIZE = 1, 3, 64  # seed 1: shapes with holes under lambertian, a creature under another model


@pytest.fixture(scope="module")
def dataset(dask_engine, tmp_path_factory):
    out = tmp_path_factory.mktemp("ds") / "data"
    prepare_dataset_dir(out)
    written, failed, _ = run_dataset(out, COUNT, SIZE, SEED, dask_engine, ProgressBar(COUNT, stream=io.StringIO()))
    assert (written, failed) == (COUNT, 0)
    return out


def _load(out, name):
    with np.load(out / name, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def test_every_sample_holds_consistent_maps_of_a_random_shape_model_and_light(dataset, real_host):
    from sketchforge.geometry.reflectance import evaluate

    manifest = json.loads((dataset / MANIFEST_NAME).read_text())
    assert manifest["format"] == "sketchforge-dataset" and manifest["seed"] == SEED and manifest["size"] == SIZE
    assert [s["index"] for s in manifest["samples"]] == list(range(COUNT)) and manifest["failed"] == []
    assert manifest["models"] == sorted(real_host.reflectance_models)
    kinds, models = set(), set()
    for rec in manifest["samples"]:
        a = _load(dataset, rec["npz"])
        assert (dataset / rec["document"]).is_file()
        assert a["shading"].shape == (SIZE, SIZE) and a["shading"].dtype == np.float32
        assert a["normal"].shape == (SIZE, SIZE, 3) and a["normal"].dtype == np.float32
        assert a["depth"].shape == (SIZE, SIZE) and a["mask"].dtype == bool and a["light"].shape == (3,)
        m, n, light = a["mask"], a["normal"].astype(np.float64), a["light"]
        model = str(a["model"])
        assert model == rec["model"] and model in real_host.reflectance_models
        assert abs(np.linalg.norm(light) - 1) < 1e-12 and light[2] >= 0 and light.tolist() == rec["light"]
        assert 0.1 < m.mean() < 0.95 and m.sum() == rec["mask_pixels"]
        assert np.abs(np.linalg.norm(n[m], axis=1) - 1).max() < 1e-5
        assert not n[~m].any() and not a["shading"][~m].any() and not a["depth"][~m].any()
        expected = np.maximum(0.0, evaluate(real_host.reflectance_models[model], n[m], light))
        if model == "lambertian":
            expected = np.maximum(0.0, n[m] @ light)  # the check, written out
        assert np.abs(a["shading"][m] - expected).max() <= 1e-6
        lit = (a["shading"][m] > 0).mean()
        assert lit > 0.05 and (lit < 0.95 or light[2] > 0)  # an in-plane light leaves a side unlit
        # depth is in pixels, so its central differences are the normals' slopes
        d = a["depth"].astype(np.float64)
        inner = m[1:-1, 1:-1] & m[:-2, 1:-1] & m[2:, 1:-1] & m[1:-1, :-2] & m[1:-1, 2:] & (n[1:-1, 1:-1, 2] > 0.4)
        dcol = (d[1:-1, 2:] - d[1:-1, :-2]) / 2
        drow = (d[2:, 1:-1] - d[:-2, 1:-1]) / 2
        nn = n[1:-1, 1:-1][inner]
        err = np.r_[np.abs(dcol[inner] + nn[:, 0] / nn[:, 2]), np.abs(drow[inner] - nn[:, 1] / nn[:, 2])]
        assert inner.sum() > 100 and np.median(err) < 0.02 and np.percentile(err, 90) < 0.2
        kinds.add(rec["kind"])
        models.add(model)
        if rec["kind"] == "holes":
            assert rec["holes"] >= 1 and rec["layers"] == 1
        else:
            assert rec["layers"] >= 4 and rec["holes"] == 0
    assert kinds == {"creature", "holes"} and "lambertian" in models and len(models) >= 2


def test_the_document_beside_a_sample_replays_to_the_very_same_maps(dataset, real_host):
    from sketchforge.document import fileformat as ff

    manifest = json.loads((dataset / MANIFEST_NAME).read_text())
    rec = next(s for s in manifest["samples"] if s["kind"] == "creature")
    data = ff.read_json(dataset / rec["document"])
    assert "snapshot" not in data and (dataset / rec["document"]).stat().st_size < 60_000  # a journal
    assert len([e for e in data["journal"] if e["command"] == "sculpt_isophote"]) == rec["edits"] >= 1
    doc = ff.load(dataset / rec["document"], host=real_host)  # replays it
    again = render_sample(doc.export_mesh(), np.asarray(doc.light.direction), real_host.reflectance_models[rec["model"]], SIZE)
    stored = _load(dataset, rec["npz"])
    for key, value in again.items():
        assert np.array_equal(value, stored[key]), key


def test_the_same_seed_gives_the_same_bytes_in_this_process_and_another_seed_other_ones(dataset):
    expected = software()
    records = []
    for i in range(COUNT):
        r = dataset_sample(SEED, i, COUNT, SIZE, expected)
        assert r.ok, r.summary
        assert r.data == (dataset / r.record["npz"]).read_bytes()
        assert r.extra == (dataset / r.record["document"]).read_bytes()
        records.append(r.record)
    manifest = json.loads((dataset / MANIFEST_NAME).read_text())
    assert manifest["generators"] == {"shape": ["creature", "holes"], "edit": ["isophote"]}
    assert manifest_bytes(SEED, COUNT, SIZE, records, [], expected, manifest["models"],
                          manifest["generators"]) == (dataset / MANIFEST_NAME).read_bytes()
    other = dataset_sample(SEED + 1, 0, COUNT, SIZE, expected)
    assert other.ok and other.data != (dataset / "sample-000000.npz").read_bytes()


def test_lights_are_uniform_on_the_hemisphere_a_document_can_hold():
    from sketchforge.document import Light

    raised = np.array([samples.draw_light(samples.streams(7, i, 0)[2]) for i in range(4000)])
    assert np.allclose(np.linalg.norm(raised, axis=1), 1, atol=1e-12) and np.all(raised[:, 2] >= 0)
    assert abs(raised[:, 2].mean() - 0.5) < 0.03 and abs((raised[:, 2] < 0.25).mean() - 0.25) < 0.03  # z uniform
    az = np.arctan2(raised[:, 1], raised[:, 0])
    counts = np.histogram(az, bins=8, range=(-math.pi, math.pi))[0]
    assert counts.min() > 4000 / 8 * 0.8 and counts.max() < 4000 / 8 * 1.2
    for v in raised[:50]:  # a document keeps them as drawn
        assert np.allclose(Light.from_vector(v).direction, v, atol=1e-15)


@pytest.mark.parametrize(
    "args, words",
    [
        (["--count", "0"], "--count must be between 1"),
        (["--count", "2", "--size", "8"], "--size must be between 16"),
        (["--count", "2", "--seed", "-1"], "--seed must be 0 or more"),
        (["--count", "2", "FULL"], "is not empty"),
    ],
)
def test_bad_arguments_are_one_line_and_write_nothing(args, words, tmp_path, capsys):
    full = tmp_path / "full"
    full.mkdir()
    (full / "keep.txt").write_text("mine")
    out = [str(full)] if "FULL" in args else [str(tmp_path / "new")]
    rc = cli.main(["dataset", *[a for a in args if a != "FULL"], *out])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and words in err[0], err
    assert not (tmp_path / "new").exists() and sorted(p.name for p in full.iterdir()) == ["keep.txt"]
