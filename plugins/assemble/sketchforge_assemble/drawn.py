"""Creatures drawn the way Monster Mash users draw them (issue 34): a seeded generator of
journals for tests and benchmarks.

People do not keep parts apart on purpose. They draw the body, then the head as an open stroke
whose ends lie on the body, the near legs in front of the body and the far legs with the right
button (behind the body), a little to the side of the near ones so that they overlap in the
drawing; twin ears or horns touch at their base; tails are open strokes; a bird has one wing
behind the body and one in front. Strokes wobble like a hand's. Every stroke goes where the
app puts it (:func:`sketchforge.geometry.parts.overlapped` for a right-button stroke: behind
the backmost part it overlaps; open or closed by :func:`~sketchforge.geometry.parts.stroke_closes`),
so a journal here is what the app would record for the same gestures.

Nothing here checks that a creature assembles: the generator draws as people do, the tests
and ``benchmarks/bench_creatures.py`` find out what the assembly makes of it.
"""

from __future__ import annotations

import numpy as np

from sketchforge.plugin_api import overlapped, stroke_closes

#: The kinds of creature drawn (a seed picks one, in turn).
KINDS = ("quadruped", "bird", "biped")

#: The inflation resolution of every part (the app's default).
RESOLUTION = 0.03


class _Drawing:
    """Strokes in the order drawn, each placed as the app places it."""

    def __init__(self, rng: np.random.Generator, resolution: float):
        self.rng = rng
        self.resolution = resolution
        self.journal: list[dict] = []
        self.outlines: list[np.ndarray] = []  # back to front, as drawn
        self.ids: list[str] = []

    def stroke(self, lid: str, points: np.ndarray, behind: bool = False, wobble: float = 0.006) -> None:
        P = _hand(points, self.rng, wobble)
        index = None
        if behind:
            hit = np.flatnonzero(overlapped(P, self.outlines))
            index = int(hit[0]) if len(hit) else 0
        closed = bool(stroke_closes(P, self.resolution))
        add: dict[str, object] = {"command": "add_layer", "id": lid, "name": lid.replace("_", " ")}
        if index is not None:
            add["index"] = index
        self.journal.append(add)
        self.journal.append({"command": "set_contour", "layer": lid, "points": np.round(P, 4).tolist(),
                             "closed": closed})
        at = len(self.outlines) if index is None else index
        self.outlines.insert(at, P)
        self.ids.insert(at, lid)

    def document(self) -> dict:
        return {"format": "sketchforge", "version": 1, "light": [0.7071, 0.7071, 0.0], "journal": self.journal}


def _hand(P: np.ndarray, rng: np.random.Generator, amp: float) -> np.ndarray:
    """P (n, 2) resampled at a mouse's spacing (~0.012) and moved sideways by a smooth random
    wobble of about ``amp`` (a few low sine waves along the arc length)."""
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    s = np.r_[0.0, np.cumsum(seg)]
    n = max(int(s[-1] / 0.012), 8)
    t = np.linspace(0.0, s[-1], n)
    Q = np.c_[np.interp(t, s, P[:, 0]), np.interp(t, s, P[:, 1])]
    if amp <= 0:
        return Q
    d = np.gradient(Q, axis=0)
    nrm = np.c_[-d[:, 1], d[:, 0]] / np.maximum(np.linalg.norm(d, axis=1), 1e-12)[:, None]
    w = np.zeros(n)
    for k in range(3):
        freq = rng.uniform(1.0, 4.0) * (k + 1) / max(s[-1], 1e-9)
        w += amp / (k + 1) * np.sin(2 * np.pi * freq * t + rng.uniform(0, 2 * np.pi))
    return Q + w[:, None] * nrm


def _blob(center, ax: float, ay: float, rng: np.random.Generator, n: int = 90, tilt: float = 0.0) -> np.ndarray:
    """A closed, slightly irregular ellipse (n, 2): a body or a head drawn in one loop."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 1.0 + sum(rng.uniform(-0.04, 0.04) * np.cos(k * t + rng.uniform(0, 2 * np.pi)) for k in (2, 3))
    x, y = ax * r * np.cos(t), ay * r * np.sin(t)
    c, s = np.cos(tilt), np.sin(tilt)
    return np.c_[center[0] + c * x - s * y, center[1] + s * x + c * y]


def _limb(root: np.ndarray, direction: float, length: float, w_root: float, w_tip: float,
          bend: float = 0.0, foot: float = 0.0) -> np.ndarray:
    """An open stroke (n, 2): from one end of the root, out along ``direction`` (radians) for
    ``length`` (bending by ``bend`` radians over it), round the tip, back to the other end of
    the root; the root segment between the ends is the junction. ``foot`` adds a toe that
    sticks out to the side at the tip (a hoof, a bird's foot)."""
    s = np.linspace(0.0, 1.0, 24)
    ang = direction + bend * s
    step = np.c_[np.cos(ang), np.sin(ang)] * (length / (len(s) - 1))
    spine = root + np.vstack([[0.0, 0.0], np.cumsum(step[:-1], axis=0)])
    tang = np.c_[np.cos(ang), np.sin(ang)]
    nrm = np.c_[-tang[:, 1], tang[:, 0]]
    w = w_root + (w_tip - w_root) * s
    # a foot: the last quarter widens to one side (a hoof, a bird's toes)
    toe = foot * np.clip((s - 0.75) / 0.25, 0.0, 1.0) ** 2
    left, right = spine + (w + toe)[:, None] * nrm, spine - w[:, None] * nrm
    cap = np.linspace(np.pi / 2, -np.pi / 2, 11)[1:-1]
    r_tip = w_tip + 0.5 * foot
    centre = spine[-1] + 0.5 * foot * nrm[-1]
    tip = centre + r_tip * (np.cos(cap)[:, None] * tang[-1] + np.sin(cap)[:, None] * nrm[-1])
    return np.vstack([left, tip, right[::-1]])


def _on(ax: float, ay: float, theta: float, frac: float) -> np.ndarray:
    return np.array([frac * ax * np.cos(theta), frac * ay * np.sin(theta)])


def _head(a: np.ndarray, b: np.ndarray, r: float, n: int = 60) -> tuple[np.ndarray, np.ndarray]:
    """(stroke (n, 2), centre (2,)): an open stroke from ``a`` round the far side of a circle
    of radius ``r`` back to ``b`` (a head drawn onto a body: its chord a-b is the junction);
    the circle's centre lies to the right of a -> b, so the arc bulges that way."""
    m, half = 0.5 * (a + b), 0.5 * np.linalg.norm(b - a)
    r = max(r, 1.05 * half)
    u = (b - a) / (2 * half)
    out = np.array([u[1], -u[0]])
    c = m + out * np.sqrt(r * r - half * half)
    t0 = np.arctan2(*(a - c)[::-1])
    t1 = np.arctan2(*(b - c)[::-1])
    if t1 < t0:
        t1 += 2 * np.pi
    # the long way round, through the side away from the chord
    t = np.linspace(t0, t1 - 2 * np.pi, n) if (t1 - t0) < np.pi else np.linspace(t0, t1, n)
    return np.c_[c[0] + r * np.cos(t), c[1] + r * np.sin(t)], c


def _junction_ends(ax: float, ay: float, theta: float, width: float, rng: np.random.Generator,
                   off: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Two points on an ellipse's arc about ``theta`` (radians), ``width`` apart along it, at a
    random fraction of the radius (0.7-0.92; once in four one end lands just outside, as a hand
    that overshoots: ``off``)."""
    dt = width / np.hypot(ax * np.sin(theta), ay * np.cos(theta))
    f1, f2 = rng.uniform(0.7, 0.92, 2)
    if off and rng.random() < 0.25:
        f2 = 1.0 + off
    return _on(ax, ay, theta - dt / 2, f1), _on(ax, ay, theta + dt / 2, f2)


def _quadruped(d: _Drawing) -> None:
    rng = d.rng
    ax, ay = rng.uniform(0.8, 1.1), rng.uniform(0.38, 0.55)
    d.stroke("body", _blob((0.0, 0.0), ax, ay, rng), wobble=0.0)
    # head: open, its chord on the body's front shoulder
    hr = rng.uniform(0.26, 0.36)
    a, b = _junction_ends(ax, ay, rng.uniform(0.35, 0.7), rng.uniform(1.0, 1.5) * hr, rng, off=0.04)
    head, hc = _head(a, b, hr)
    d.stroke("head", head)
    # ears or horns: twins on top of the head whose bases touch (or nearly, or overlap a little)
    top = hc + hr * np.array([np.cos(1.7), np.sin(1.7)]) * 0.72
    w = rng.uniform(0.05, 0.08)
    touch = rng.uniform(-0.3, 0.3) * w  # < 0: the bases overlap
    for k, side in enumerate((-1, 1)):
        root = top + np.array([side * (w + 0.5 * touch), 0.0])
        ear = _limb(root, np.pi / 2 - side * rng.uniform(0.15, 0.5), rng.uniform(0.22, 0.35), w, 0.4 * w,
                    bend=side * rng.uniform(-0.3, 0.3))
        d.stroke(f"ear_{k}", ear, behind=(k == 1 and rng.random() < 0.3))
    # legs: a near and a far one at the front and at the back; the far one drawn with the right
    # button, shifted by a fraction of a leg's width so that the two overlap in the drawing
    for name, x0 in (("front", rng.uniform(0.35, 0.6) * ax), ("hind", -rng.uniform(0.35, 0.6) * ax)):
        lw = rng.uniform(0.08, 0.12)
        y_root = -ay * rng.uniform(0.15, 0.55)
        length = rng.uniform(0.45, 0.7) + abs(y_root)
        direction = -np.pi / 2 + rng.uniform(-0.15, 0.15)
        root = np.array([x0, y_root])
        d.stroke(f"{name}_near", _limb(root, direction, length, lw, 0.8 * lw, foot=rng.choice([0.0, 1.2 * lw])))
        shift = np.array([rng.uniform(-1.2, 1.2) * lw, rng.uniform(-0.1, 0.1)])
        d.stroke(f"{name}_far", _limb(root + shift, direction + rng.uniform(-0.2, 0.2), length * rng.uniform(0.9, 1.0),
                                      lw, 0.8 * lw), behind=True)
    # tail: open, at the rear, in front or behind
    tail_root = _on(ax, ay, np.pi + rng.uniform(-0.3, 0.4), 0.85)
    d.stroke("tail", _limb(tail_root, np.pi + rng.uniform(0.2, 0.8), rng.uniform(0.4, 0.7), 0.05, 0.025,
                           bend=rng.uniform(-0.8, 0.8)), behind=rng.random() < 0.5)
    # a snout: open, on the front of the head
    snout_root = hc + 0.55 * hr * np.array([np.cos(-0.3), np.sin(-0.3)])
    d.stroke("snout", _limb(snout_root, rng.uniform(-0.5, 0.1), rng.uniform(0.12, 0.2), rng.uniform(0.08, 0.11),
                            rng.uniform(0.06, 0.09)))
    # eyes: closed, on the head (the far one drawn behind it, peeking over its outline)
    e = hc + 0.45 * hr * np.array([np.cos(0.5), np.sin(0.5)])
    d.stroke("eye", _blob(e, 0.05, 0.04, rng, n=24), wobble=0.0)
    d.stroke("eye_far", _blob(e + np.array([0.12, 0.02]), 0.035, 0.035, rng, n=24), behind=True, wobble=0.0)


def _bird(d: _Drawing) -> None:
    rng = d.rng
    ax, ay = rng.uniform(0.7, 0.95), rng.uniform(0.4, 0.52)
    tilt = rng.uniform(-0.25, 0.1)
    d.stroke("body", _blob((0.0, 0.0), ax, ay, rng, tilt=tilt), wobble=0.0)
    hr = rng.uniform(0.25, 0.32)
    a, b = _junction_ends(ax, ay, rng.uniform(0.5, 0.9) + tilt, rng.uniform(1.0, 1.5) * hr, rng, off=0.04)
    head, hc = _head(a, b, hr)
    d.stroke("head", head)
    beak_root = hc + 0.75 * hr * np.array([1.0, 0.0])
    d.stroke("beak", _limb(beak_root, rng.uniform(-0.3, 0.2), rng.uniform(0.2, 0.35), 0.07, 0.01))
    # a wing in front of the body and one behind it (right button), overlapping in the drawing
    wroot = np.array([rng.uniform(-0.1, 0.25) * ax, rng.uniform(0.0, 0.3) * ay])
    wdir = np.pi * rng.uniform(0.8, 0.95)
    d.stroke("wing_near", _limb(wroot, wdir, rng.uniform(0.7, 1.0), rng.uniform(0.16, 0.22), 0.05,
                                bend=rng.uniform(-0.4, 0.1)))
    d.stroke("wing_far", _limb(wroot + rng.uniform(-0.1, 0.1, 2), wdir + rng.uniform(-0.4, 0.2), rng.uniform(0.6, 0.9),
                               rng.uniform(0.14, 0.2), 0.05, bend=rng.uniform(-0.3, 0.3)), behind=True)
    # tail feathers: open, at the rear
    troot = _on(ax, ay, np.pi + rng.uniform(-0.4, 0.0), 0.8)
    d.stroke("tail", _limb(troot, np.pi + rng.uniform(-0.6, -0.1), rng.uniform(0.4, 0.6), 0.08, 0.12),
             behind=rng.random() < 0.5)
    # legs: a near one and a far one, overlapping
    for k in range(2):
        root = np.array([rng.uniform(-0.2, 0.3) * ax + 0.12 * k, -ay * rng.uniform(0.4, 0.7)])
        d.stroke(f"leg_{'near' if k == 0 else 'far'}", _limb(root, -np.pi / 2 + rng.uniform(-0.2, 0.2),
                                                            rng.uniform(0.45, 0.65), 0.05, 0.035, foot=0.09),
                 behind=(k == 1))
    e = hc + 0.4 * hr * np.array([np.cos(0.6), np.sin(0.6)])
    d.stroke("eye", _blob(e, 0.045, 0.045, rng, n=24), wobble=0.0)


def _biped(d: _Drawing) -> None:
    rng = d.rng
    ax, ay = rng.uniform(0.38, 0.5), rng.uniform(0.55, 0.75)
    d.stroke("body", _blob((0.0, 0.0), ax, ay, rng), wobble=0.0)
    hr = rng.uniform(0.3, 0.38)
    a, b = _junction_ends(ax, ay, np.pi / 2 + rng.uniform(-0.15, 0.15), rng.uniform(1.0, 1.4) * hr, rng, off=0.04)
    head, hc = _head(a, b, hr)
    d.stroke("head", head)
    # long ears touching at their base, or horns
    top = hc + np.array([0.0, 0.75 * hr])
    w = rng.uniform(0.06, 0.09)
    touch = rng.uniform(-0.3, 0.3) * w
    for k, side in enumerate((-1, 1)):
        root = top + np.array([side * (w + 0.5 * touch), 0.0])
        d.stroke(f"ear_{k}", _limb(root, np.pi / 2 - side * rng.uniform(0.05, 0.4), rng.uniform(0.35, 0.6), w, 0.6 * w,
                                   bend=-side * rng.uniform(0.0, 0.5)), behind=(k == 1 and rng.random() < 0.5))
    # arms: the near one in front of the body, the far one behind, overlapping
    for k, side in enumerate((1, -1)):
        root = np.array([side * ax * rng.uniform(0.45, 0.7), ay * rng.uniform(0.2, 0.45)])
        d.stroke(f"arm_{'near' if k == 0 else 'far'}",
                 _limb(root, -np.pi / 2 + side * rng.uniform(0.4, 1.0), rng.uniform(0.5, 0.7), 0.08, 0.06,
                       bend=side * rng.uniform(-0.4, 0.4)), behind=(k == 1))
    # legs: near and far, close together below the body
    for k in range(2):
        root = np.array([rng.uniform(-0.4, 0.4) * ax, -ay * rng.uniform(0.5, 0.75)])
        d.stroke(f"leg_{'near' if k == 0 else 'far'}",
                 _limb(root, -np.pi / 2 + rng.uniform(-0.2, 0.2), rng.uniform(0.45, 0.6), 0.1, 0.08,
                       foot=rng.choice([0.0, 0.12])), behind=(k == 1))
    e = hc + 0.4 * hr * np.array([np.cos(0.4), np.sin(0.4)])
    d.stroke("eye", _blob(e, 0.05, 0.06, rng, n=24), wobble=0.0)


def drawn_creature(seed: int, kind: str | None = None, resolution: float = RESOLUTION) -> dict:
    """A document (dict, journal form) of a creature drawn with Monster Mash habits (module
    docstring). ``kind`` (one of :data:`KINDS`) defaults to ``KINDS[seed % 3]``. Deterministic
    for a given seed; 9-13 parts."""
    kind = KINDS[seed % len(KINDS)] if kind is None else kind
    if kind not in KINDS:
        raise ValueError(f"unknown creature kind {kind!r} (known: {', '.join(KINDS)})")
    d = _Drawing(np.random.default_rng([34, seed]), resolution)
    {"quadruped": _quadruped, "bird": _bird, "biped": _biped}[kind](d)
    if resolution != RESOLUTION:
        for lid in d.ids:
            d.journal.append({"command": "set_inflate_params", "layer": lid,
                              "params": {"resolution": resolution, "inflation": 1.0, "smoothing": 0.5}})
    return d.document()
