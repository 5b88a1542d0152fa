"""Distances between neighbouring strips inside a zone, batched and memoised.

Both seeding loops (region strips near the stroke, 4.3.3; characteristic strips covering M•,
4.5) insert a strip wherever two neighbours are too far apart (:func:`insert_strips`), then
measure again. Measuring
pair by pair cost one GEOS call per strip pair and round (~30 ms per edit at 5k vertices); here
every pair still unmeasured goes into one vectorised ``shapely.distance`` call, and a pair
measured in an earlier round is not measured again.
"""

from __future__ import annotations

import numpy as np
import shapely


class StripGaps:
    """Largest distance from the samples of one strip inside ``zone`` to the other strip.

    Parameters
    ----------
    zone : shapely geometry
        Only samples inside it count (prepared here).

    Notes
    -----
    Strips are keyed by identity: pass the same array objects from round to round (the
    memo keeps a reference to each, so an id is never reused while the object lives).
    """

    def __init__(self, zone) -> None:
        self.zone = zone
        shapely.prepare(zone)
        self._lines: dict[int, tuple[np.ndarray, object]] = {}
        self._memo: dict[tuple[int, int], tuple[float, np.ndarray, np.ndarray]] = {}

    def _line(self, s: np.ndarray):
        hit = self._lines.get(id(s))
        if hit is None:
            hit = (s, shapely.LineString(s[:, :2]) if len(s) >= 2 else None)
            self._lines[id(s)] = hit
        return hit[1]

    def __call__(self, pairs: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
        """Gaps of many strip pairs.

        Parameters
        ----------
        pairs : list of ((j, 2+) float64, (k, 2+) float64)
            Neighbouring strips (x, y in the first two columns).

        Returns
        -------
        (len(pairs),) float64
            0 for a pair with no sample in the zone.
        """
        out = np.zeros(len(pairs))
        todo, pts, lines, owner = [], [], [], []
        for k, (a, b) in enumerate(pairs):
            m = self._memo.get((id(a), id(b)))
            if m is not None:
                out[k] = m[0]
                continue
            todo.append(k)
            for p, q in ((a, b), (b, a)):
                line = self._line(q)
                if len(p) == 0 or line is None:
                    continue
                pts.append(p[:, :2])
                lines.append(np.full(len(p), line, dtype=object))
                owner.append(np.full(len(p), k))
        if pts:
            P, L, own = np.concatenate(pts), np.concatenate(lines), np.concatenate(owner)
            inside = shapely.contains_xy(self.zone, P[:, 0], P[:, 1])
            if inside.any():
                d = shapely.distance(shapely.points(P[inside]), L[inside])
                np.maximum.at(out, own[inside], d)
        for k in todo:
            a, b = pairs[k]
            self._memo[(id(a), id(b))] = (float(out[k]), a, b)
        return out


def insert_strips(t: np.ndarray, strips: list, new_t: np.ndarray, new_strips: list) -> tuple[np.ndarray, list]:
    """Merge strips seeded at parameters ``new_t`` into strips seeded at ``t``, sorted by seed
    parameter (both seeding loops refine by inserting strips between too-distant neighbours)."""
    t2 = np.concatenate([t, new_t])
    order = np.argsort(t2, kind="stable")
    s2 = list(strips) + list(new_strips)
    return t2[order], [s2[i] for i in order]
