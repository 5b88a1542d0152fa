"""Write tests/data/silhouettes.json: outlines nobody here drew, for the inflation corpus.

Run by hand, in a throwaway virtual environment (neither package is a dependency of
sketchforge or of its tests; the JSON it writes is committed instead):

    python3 -m venv /tmp/silvenv && /tmp/silvenv/bin/pip install scikit-image fonttools
    /tmp/silvenv/bin/python tests/data/make_silhouettes.py

Sources (all deterministic):
- scikit-image's horse (``skimage.data.horse()``, a binary image): its outer contour from
  ``skimage.measure.find_contours``, y up, scaled to 2 drawing units wide. Its legs come within
  ~0.015 of each other, closer than the default resolution.
- ``skimage.data.binary_blobs`` with fixed seeds: the larger blobs that do not touch the image's
  border (necks, near-touching lobes, the odd hole), each scaled to 2 units across.
- Glyphs of DejaVu Sans and DejaVu Serif (the fonts Debian's fonts-dejavu-core installs), their
  quadratic outlines flattened, scaled so that the cap height is 1.5 units: the outer ring is
  the stroke, the inner rings (B, O, 8, ...) the holes.

Each entry: ``name``, ``source``, ``points`` (the outer ring, counter-clockwise, first point
not repeated) and ``holes`` (inner rings, possibly empty). Coordinates are rounded to 1e-3; the
script checks that every ring is still simple after rounding and that the holes lie inside.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import shapely

OUT = Path(__file__).with_name("silhouettes.json")
FONTS = {
    "DejaVu Sans": "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "DejaVu Serif": "/usr/share/fonts/truetype/dejavu/DejaVuSerif.ttf",
}
#: Letters with holes (outer ring + inner rings) and without, in both fonts.
GLYPHS = "ABDOPQRabego068&" + "CEGKLMNSWZ235kmnsxyw"
BLOB_SEEDS = (3, 11)
BLOBS_PER_SEED = 3
DIGITS = 3


def _area(P) -> float:
    x, y = P[:, 0], P[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _ccw(P):
    P = np.asarray(P, dtype=np.float64)
    if np.allclose(P[0], P[-1]):
        P = P[:-1]
    return P if _area(P) > 0 else P[::-1]


def _entry(name, source, outer, holes, scale_to=None, scale=None):
    """Centre, scale, round, check; returns the JSON entry."""
    outer = _ccw(outer)
    holes = [_ccw(h)[::-1] for h in holes]  # clockwise, as a layer's holes are kept
    lo, hi = outer.min(axis=0), outer.max(axis=0)
    centre = 0.5 * (lo + hi)
    s = scale if scale is not None else scale_to / float(np.max(hi - lo))
    rings = [np.round((R - centre) * s, DIGITS) for R in [outer, *holes]]
    # Rounding can make consecutive points equal: drop those.
    rings = [R[np.any(R != np.roll(R, 1, axis=0), axis=1)] for R in rings]
    outer_poly = shapely.Polygon(rings[0])
    for R in rings:
        ring = shapely.LinearRing(R)
        if not ring.is_simple:
            raise SystemExit(f"{name}: a ring is not simple after rounding")
    for R in rings[1:]:
        if not outer_poly.contains(shapely.Polygon(R)):
            raise SystemExit(f"{name}: a hole is not inside the outline")
    return {"name": name, "source": source, "points": rings[0].tolist(), "holes": [R.tolist() for R in rings[1:]]}


def horse():
    from skimage import data, measure

    img = np.pad(~data.horse(), 2).astype(np.float64)  # the horse is False (dark) on white
    contours = measure.find_contours(img, 0.5)
    outer = max(contours, key=len)
    xy = np.column_stack([outer[:, 1], -outer[:, 0]])
    return _entry("horse", "skimage.data.horse", xy, [], scale_to=2.0)


def blobs():
    from skimage import data, measure

    out = []
    for seed in BLOB_SEEDS:
        img = data.binary_blobs(length=256, blob_size_fraction=0.15, volume_fraction=0.3, rng=seed)
        labels = measure.label(img)
        regions = [r for r in measure.regionprops(labels)
                   if r.bbox[0] > 0 and r.bbox[1] > 0 and r.bbox[2] < img.shape[0] and r.bbox[3] < img.shape[1]]
        regions.sort(key=lambda r: -r.area)
        for n, r in enumerate(regions[:BLOBS_PER_SEED]):
            mask = np.pad(labels == r.label, 2).astype(np.float64)
            contours = measure.find_contours(mask, 0.5)
            rings = [np.column_stack([c[:, 1], -c[:, 0]]) for c in contours]
            rings.sort(key=lambda R: -abs(_area(R)))
            outer, holes = rings[0], [R for R in rings[1:] if abs(_area(R)) > 4.0]
            out.append(_entry(f"blob-{seed}-{n}", f"skimage.data.binary_blobs(rng={seed})", outer, holes, scale_to=2.0))
    return out


def _flatten_glyph(glyph_set, name, tolerance):
    """The glyph's contours as polylines (font units), quadratic curves flattened."""
    from fontTools.pens.basePen import BasePen

    class Flatten(BasePen):
        def __init__(self):
            super().__init__(glyph_set)
            self.contours, self.cur = [], []

        def _moveTo(self, p):
            self.cur = [p]

        def _lineTo(self, p):
            self.cur.append(p)

        def _qCurveToOne(self, p1, p2):
            p0 = np.asarray(self.cur[-1], dtype=np.float64)
            a, b = np.asarray(p1, dtype=np.float64), np.asarray(p2, dtype=np.float64)
            n = max(2, int(np.ceil((np.linalg.norm(a - p0) + np.linalg.norm(b - a)) / tolerance)))
            for t in np.linspace(0.0, 1.0, n + 1)[1:]:
                self.cur.append(tuple((1 - t) ** 2 * p0 + 2 * (1 - t) * t * a + t * t * b))

        def _curveToOne(self, p1, p2, p3):
            p0 = np.asarray(self.cur[-1], dtype=np.float64)
            a, b, c = (np.asarray(p, dtype=np.float64) for p in (p1, p2, p3))
            n = max(3, int(np.ceil((np.linalg.norm(a - p0) + np.linalg.norm(b - a) + np.linalg.norm(c - b)) / tolerance)))
            for t in np.linspace(0.0, 1.0, n + 1)[1:]:
                self.cur.append(tuple((1 - t) ** 3 * p0 + 3 * (1 - t) ** 2 * t * a + 3 * (1 - t) * t * t * b + t ** 3 * c))

        def _closePath(self):
            if len(self.cur) > 2:
                self.contours.append(np.asarray(self.cur, dtype=np.float64))
            self.cur = []

        _endPath = _closePath

    pen = Flatten()
    glyph_set[name].draw(pen)
    return pen.contours


def glyphs():
    from fontTools.ttLib import TTFont

    out = []
    for font_name, path in FONTS.items():
        font = TTFont(path)
        cmap = font.getBestCmap()
        glyph_set = font.getGlyphSet()
        # DejaVu's OS/2 table predates sCapHeight: the cap height is the top of 'H'.
        glyf = font["glyf"]
        h = glyf[cmap[ord("H")]]
        cap = float(h.yMax - h.yMin)
        scale = 1.5 / cap
        # Curves flattened into pieces of about 0.02 drawing units (a
        # curve of radius 0.1 is then within 5e-4 of its chords).
        tolerance = 0.02 / scale
        for ch in GLYPHS:
            rings = _flatten_glyph(glyph_set, cmap[ord(ch)], tolerance)
            rings = [R[np.any(R != np.roll(R, 1, axis=0), axis=1)] for R in rings]
            rings.sort(key=lambda R: -abs(_area(R)))
            outer = shapely.Polygon(rings[0])
            holes = [R for R in rings[1:] if outer.contains(shapely.Polygon(R))]
            if len(holes) != len(rings) - 1:
                raise SystemExit(f"{font_name} {ch!r}: more than one outer ring")
            label = "sans" if "Sans" in font_name else "serif"
            out.append(_entry(f"{label}-{ch}", f"{font_name} '{ch}'", rings[0], holes, scale=scale))
    return out


def main() -> int:
    entries = [horse(), *blobs(), *glyphs()]
    text = json.dumps({"about": "outlines for tests/test_silhouettes.py, written by tests/data/make_silhouettes.py",
                       "silhouettes": entries}, separators=(",", ":"))
    OUT.write_text(text + "\n")
    holes = sum(1 for e in entries if e["holes"])
    print(f"{OUT}: {len(entries)} silhouettes ({holes} with holes), {len(text) / 1024:.0f} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
