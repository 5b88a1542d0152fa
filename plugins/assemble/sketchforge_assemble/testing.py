"""Test support: the layers of a document (dict or JSON path), replayed through the document
itself with only the inflate plugin, so tests and benchmarks of the assembly see exactly the
layers the app would pass to the hook."""

from __future__ import annotations

from pathlib import Path


def document_from(doc):
    """Replay a document's journal headlessly (inflate plugin only) and return the Document."""
    from sketchforge.plugin_api import document_from_dict, load_document, make_host

    host = make_host(installed=("inflate",))
    if isinstance(doc, dict):
        return document_from_dict(doc, host=host, use_snapshot=False)
    return load_document(Path(doc), host=host, use_snapshot=False)


def layers_from_journal(doc) -> list:
    """The document's layers (``sketchforge.document.Layer``), back to front."""
    return list(document_from(doc).layers)


def meshes_from_journal(doc):
    """(layers, meshes, closed) of the layers that have a mesh, back to front."""
    layers = [layer for layer in layers_from_journal(doc) if layer.mesh is not None]
    return layers, [layer.mesh for layer in layers], [layer.closed for layer in layers]


def random_creature(seed: int, resolution: float = 0.03) -> dict:
    """A document (dict, journal form) of a random creature: an elliptic body, a head, 2-6
    limbs (some behind the body, some in front) and an eye on the head.

    Every part is an open stroke whose closing segment (its junction) lies inside the body at
    0.7 of its radius, so it attaches; limbs are spread about 40 degrees apart around the body
    and one that would put its junction over another part (or cover another part's
    junction) is left out, so a creature may have fewer limbs than drawn (at least 2 in
    practice). Deterministic for a given ``seed``.

    Raises
    ------
    ValueError
        For the few seeds whose head cannot be placed (e.g. 43).
    """
    import numpy as np

    rng = np.random.default_rng(seed)
    ax, ay = rng.uniform(0.8, 1.1), rng.uniform(0.5, 0.7)
    journal = []

    def layer(lid, points, closed):
        journal.append({"command": "add_layer", "id": lid, "name": lid.replace("_", " ").title()})
        journal.append({"command": "set_contour", "layer": lid,
                        "points": np.round(points, 4).tolist(), "closed": closed})
        res = resolution if lid != "eye" else resolution / 2
        journal.append({"command": "set_inflate_params", "layer": lid,
                        "params": {"resolution": res, "inflation": 1.0, "smoothing": 0.5}})

    def on_body(theta, frac):
        return np.array([frac * ax * np.cos(theta), frac * ay * np.sin(theta)])

    t = np.linspace(0, 2 * np.pi, 72, endpoint=False)
    layer("body", np.c_[ax * np.cos(t), ay * np.sin(t)], True)

    # head: an arc of a circle centred on the body's outline, its chord inside the body
    th = rng.uniform(np.radians(20), np.radians(60))
    c = on_body(th, 1.0)
    r = rng.uniform(0.3, 0.42)
    out = np.arctan2(c[1] / ay**2, c[0] / ax**2)  # outward normal of the ellipse at c
    a = np.linspace(out - np.radians(120), out + np.radians(120), 50)
    import shapely

    inner = shapely.Polygon(np.c_[ax * np.cos(t), ay * np.sin(t)]).buffer(-0.05)
    while not inner.contains(shapely.LineString([c + r * np.array([np.cos(a[0]), np.sin(a[0])]),
                                                 c + r * np.array([np.cos(a[-1]), np.sin(a[-1])])])):
        r *= 0.9  # a head so large that its junction would leave the body
        if r < 0.1:
            # the chord of a smaller head lies within the 0.05 band along the outline, where
            # no head fits: shrinking further would never end (seed 43)
            raise ValueError(f"random creature {seed}: no head fits on the body; take another seed")
    layer("head", np.c_[c[0] + r * np.cos(a), c[1] + r * np.sin(a)], False)

    # limbs: capsules pointing outwards from inside the body, spread around its lower half; a
    # candidate whose junction would lie over another part (or whose outline would cover
    # another part's junction) is skipped, so every junction lies on the body alone

    head_poly = shapely.Polygon(np.c_[c[0] + r * np.cos(a), c[1] + r * np.sin(a)])
    taken_polys, taken_lines = [head_poly], [shapely.LineString([head_poly.exterior.coords[0],
                                                                 head_poly.exterior.coords[-2]])]
    n_limbs = int(rng.integers(2, 7))
    slots = np.radians(np.arange(150, 391, 40.0))  # 150..390 degrees: away from the head
    order = rng.permutation(len(slots))
    behind = []
    k = 0
    for slot in order:
        if k == n_limbs:
            break
        theta = slots[slot] + rng.uniform(-0.1, 0.1)
        p = on_body(theta, 0.7)
        d = np.array([np.cos(theta), np.sin(theta)])
        nrm = np.array([-d[1], d[0]])
        w = rng.uniform(0.09, 0.14)  # half width
        length = rng.uniform(0.5, 0.8)
        tip = p + length * d
        s = np.linspace(0, 1, 14)[:, None]
        side1 = p + w * nrm + s * (tip - p)
        cap = np.linspace(np.pi / 2, -np.pi / 2, 12)[1:-1]
        end = tip + w * (np.cos(cap)[:, None] * d + np.sin(cap)[:, None] * nrm)
        side2 = p - w * nrm + s[::-1] * (tip - p)
        pts = np.vstack([side1, end, side2])
        poly, line = shapely.Polygon(pts), shapely.LineString([pts[-1], pts[0]])
        if any(poly.distance(t) < 0.05 for t in taken_lines) or any(line.distance(t) < 0.05 for t in taken_polys):
            continue
        taken_polys.append(poly)
        taken_lines.append(line)
        lid = f"limb_{k}"
        k += 1
        layer(lid, pts, False)
        if rng.random() < 0.5:
            behind.append(lid)

    # eye: a small ellipse well inside the head
    e = c + 0.35 * r * np.array([np.cos(out), np.sin(out)])
    t = np.linspace(0, 2 * np.pi, 18, endpoint=False)
    layer("eye", np.c_[e[0] + 0.08 * np.cos(t), e[1] + 0.06 * np.sin(t)], True)
    for lid in behind:
        journal.append({"command": "move_layer", "layer": lid, "index": 0})
    return {"format": "sketchforge", "version": 1, "light": [0.7071, 0.7071, 0.0], "journal": journal}
