"""Characteristic strips integrated with diffrax (thesis 4.5), jitted and vmapped over strips.

Each strip is a base characteristic of the surface before the edit, dx/ds = −R_p,
dy/ds = −R_q (3.1.2, 4.3.3). The linearised system the edit solves is triangular: the path
depends on the old surface only, and the height change along it, dδz/ds = −δE, is a
quadrature on the path (:func:`strip_integrals`). So the ODE integrated here is the path
alone, once per edit, and the shading change is read on its saved points afterwards (the
first release integrated the paths twice: once to find S•, once with δE on board).

The strips are parametrised by arc length σ (dx/dσ the unit direction; ds = dσ / |∇R|) and
integrated in segments of a fixed number of saved points (:data:`SEGMENT`) a fixed arc
length apart, for a fixed number of strips at a time (:data:`BATCH`, padded): one compiled
function per integrator serves every layer, stroke and strip count (the tolerances, the
field's grid, the sample spacing are arguments). A strip goes on segment after segment until
it stops: in the rim margin (the rim mask falls to 0 and stops it, 4.3's Ω*), at a point where
the flow vanishes (a tilted light's brightest point), or at the length cap. So the work grows
with the strips' actual length, not with a length guessed for the whole layer.

Solvers: ``tsit5`` (explicit, the default: the system is not stiff and Tsit5 was 2–4× faster
than Kvaerno5 with the same accuracy on the prototype) and ``kvaerno5`` (the thesis' implicit
A-L-stable solver), on the C² field of :mod:`.field`. By default one step per saved point
(a fifth-order step of half an edge length on a field that is smooth on the scale of an edge):
an adaptive controller accepts or rejects steps by comparing an error estimate with its
tolerance, a decision that round-off flips, and a stroke moved by 1e-12 moved the strips by
6e-5 and the heights by 1e-5 of the peak. diffrax's PID controller remains a choice
(``step_control: "pid"``, with ``rtol`` and ``atol``), and Kvaerno5 always uses it (its implicit
stages take the controller's tolerances).

Compilation: the first process ever traces the function through diffrax (~0.6 s of CPU,
after ~0.4 s importing diffrax) and compiles it (~1–2 s). Two caches under the user's cache
directory keep that work for every later process (the app, ``sketchforge replay``, a
benchmark's workers): JAX's persistent compilation cache (:func:`enable_compilation_cache`)
keeps the compiled code, and the traced function itself is kept as a ``jax.export`` artifact
(StableHLO, :func:`_segment_function`), so a later process neither imports diffrax nor traces:
its first edit loads the artifact and finds the compiled code (~0.25 s of CPU instead of ~1.3 s;
issue 36 counts that first edit in the time per edit). Every process, the first included,
runs the exported function, so all run the very same code. equinox's runtime checks would put
a host callback into the compiled code, which neither cache can store; they are switched to
``nan`` (``EQX_ON_ERROR``, unless the environment sets it) — the solve runs with
``throw=False`` and reads its own status instead.
"""

from __future__ import annotations

import functools
import hashlib
import os
import threading
from pathlib import Path

import numpy as np

#: |∇R| below which the strip's speed is floored (1/|∇R| turns a shading change into a
#: height change; where the shading does not depend on the slope no edit can act).
SPEED_FLOOR = 1e-3
#: Strips integrated by one compiled call (a batch is padded to it): one shape, one compile.
#: A call's cost grows with the batch whether its lanes are real strips or padding (measured
#: per call: 2.7, 3.9 and 8.6 ms of CPU for 16, 32 and 64 strips of 128 steps): 32 wastes
#: less on padding than 64 (an edit's 40–100 strip halves filled two calls of 64, half of
#: the second one padding) at the same cost per strip.
BATCH = 32
#: Points saved per strip and call; a strip's path is built segment by segment.
SEGMENT = 128
#: Steps a strip may take in one segment before it is cut off where it is.
MAX_STEPS = 4096


def cache_directory() -> Path:
    """Where compiled strip functions are kept across processes:
    ``$SKETCHFORGE_CACHE_DIR/jax``, else ``$XDG_CACHE_HOME/sketchforge/jax``, else
    ``~/.cache/sketchforge/jax``."""
    own = os.environ.get("SKETCHFORGE_CACHE_DIR")
    if own:
        return Path(own) / "jax"
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "sketchforge" / "jax"


_CACHE_SET = False


def enable_compilation_cache(jax) -> None:
    """Point JAX's persistent compilation cache at :func:`cache_directory` (once per process),
    unless one is configured already (``JAX_COMPILATION_CACHE_DIR``). A directory that cannot
    be created leaves the cache off: it only saves time."""
    global _CACHE_SET
    if _CACHE_SET:
        return
    _CACHE_SET = True
    if jax.config.jax_compilation_cache_dir:
        return
    path = cache_directory()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return
    jax.config.update("jax_compilation_cache_dir", str(path))
    # The strip function compiles in 1-2 s; the defaults (cache only compiles over 1 s) would
    # skip it on a fast machine.
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)


def _jax():
    os.environ.setdefault("EQX_ON_ERROR", "nan")  # before equinox is imported (see the docstring)
    import jax

    jax.config.update("jax_enable_x64", True)  # before any array: the strips are float64
    enable_compilation_cache(jax)
    return jax


def _traced_segment_function(integrator: str, adaptive: bool = False):
    """The jitted, vmapped integration of one segment of :data:`BATCH` strips through diffrax:
    one step per saved point, or (``adaptive``) diffrax's PID step controller."""
    jax = _jax()
    import diffrax
    import jax.numpy as jnp

    from .field import bspline_eval

    def rhs(t, y, args):
        coeffs, origin, spacing, length, sign = args
        v = bspline_eval(coeffs, origin, spacing, y)
        d = -v[:2]  # (−R_p, −R_q): the base characteristic's direction
        speed = jnp.sqrt(d[0] * d[0] + d[1] * d[1] + SPEED_FLOOR * SPEED_FLOOR)
        m = jnp.clip(v[2], 0.0, 1.0)  # the rim mask stops the strip in the rim margin
        return sign * length * m * d / speed

    solver = {"tsit5": diffrax.Tsit5, "kvaerno5": diffrax.Kvaerno5}[integrator]()
    ts = jnp.linspace(0.0, 1.0, SEGMENT + 1)[1:]

    def one(y0, sign, coeffs, origin, spacing, length, rtol, atol):
        if adaptive:
            control, dt0 = diffrax.PIDController(rtol=rtol, atol=atol), None
        else:
            control, dt0 = diffrax.ConstantStepSize(), 1.0 / SEGMENT
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs), solver, t0=0.0, t1=1.0, dt0=dt0, y0=y0,
            args=(coeffs, origin, spacing, length, sign),
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=control,
            max_steps=MAX_STEPS, throw=False,
        )
        return sol.ys, sol.stats["num_steps"]

    return jax.jit(jax.vmap(one, in_axes=(0, 0, None, None, None, None, None, None)))


def _argument_specs(jax):
    """The shapes and dtypes of a segment call's arguments (y0, sign, coeffs, origin, spacing,
    length, rtol, atol): the one shape the exported function takes."""
    from .field import GRID_SIZE

    f64 = jax.numpy.float64
    S = jax.ShapeDtypeStruct
    return (S((BATCH, 2), f64), S((BATCH,), f64), S((GRID_SIZE, GRID_SIZE, 3), f64), S((2,), f64),
            S((), f64), S((), f64), S((), f64), S((), f64))


#: The artifact's first bytes, then a blake2b digest of the serialized function: a file cut
#: short or changed on disk is seen as such and traced anew, never run.
_MAGIC = b"sketchforge-strips-export-1\n"
_DIGEST = 32


def export_path(integrator: str, adaptive: bool) -> Path:
    """Where the exported segment function of ``integrator`` is kept (beside the compilation
    cache, ``.../sketchforge/strips/``): named by everything that makes it (the versions of
    jax, jaxlib and the diffrax stack, the backend, this module's and :mod:`.field`'s source,
    the batch and segment shapes, ``EQX_ON_ERROR``), so a change to any of them finds no
    artifact and traces anew instead of running stale code."""
    import importlib.metadata as md

    jax = _jax()  # EQX_ON_ERROR, which the key holds, is set there
    h = hashlib.blake2b(digest_size=12)
    for dist in ("jax", "jaxlib", "diffrax", "equinox", "lineax", "optimistix"):
        try:
            h.update(f"{dist}={md.version(dist)};".encode())
        except md.PackageNotFoundError:
            h.update(f"{dist}=?;".encode())
    h.update(f"{jax.default_backend()};{BATCH};{SEGMENT};{MAX_STEPS};{SPEED_FLOOR!r};"
             f"{os.environ.get('EQX_ON_ERROR')};".encode())
    here = Path(__file__).resolve().parent
    for name in ("integrate.py", "field.py"):
        h.update((here / name).read_bytes())
    return cache_directory().parent / "strips" / f"{integrator}-{'pid' if adaptive else 'fixed'}-{h.hexdigest()}.jaxexport"


def _load_exported(path: Path, jax):
    """The exported function kept at ``path``, or None where there is none that this process
    can run: missing, unreadable, cut short, changed on disk (its digest), not deserializable,
    or made for other argument shapes or another backend."""
    from jax import export

    try:
        data = path.read_bytes()
    except OSError:
        return None
    head, digest, body = data[:len(_MAGIC)], data[len(_MAGIC):len(_MAGIC) + _DIGEST], data[len(_MAGIC) + _DIGEST:]
    if head != _MAGIC or hashlib.blake2b(body, digest_size=_DIGEST).digest() != digest:
        return None
    try:
        exported = export.deserialize(bytearray(body))
        specs = _argument_specs(jax)
        if (len(exported.in_avals) != len(specs) or jax.default_backend() not in exported.platforms
                or any(a.shape != s.shape or a.dtype != s.dtype for a, s in zip(exported.in_avals, specs))):
            return None
    except Exception:  # noqa: BLE001  (a format this jax cannot read: a cache, traced anew)
        return None
    return exported


def _store_exported(exported, path: Path) -> None:
    """Keep ``exported`` at ``path`` for the next process. Best effort: a cache directory that
    cannot be written, or a jax without serialization (flatbuffers), only costs the next
    process the tracing. Written beside its final name and renamed, so a process reading it
    never sees half a file."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")  # one writer each
    try:
        body = bytes(exported.serialize())
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_bytes(_MAGIC + hashlib.blake2b(body, digest_size=_DIGEST).digest() + body)
        os.replace(tmp, path)
    except Exception:  # noqa: BLE001  (OSError, ImportError: the cache only saves time)
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass


@functools.lru_cache(maxsize=8)
def _segment_function(integrator: str, adaptive: bool = False):
    """The segment function of :func:`_traced_segment_function`, run from its ``jax.export``
    artifact: loaded from :func:`export_path` when a process before this one made it, else
    traced, exported and stored there. Either way the process runs the exported function (the
    same StableHLO, so the same strips to the bit). Only a function that cannot be exported
    (``EQX_ON_ERROR`` set to ``raise`` by the environment puts a host callback in it) runs as
    traced."""
    jax = _jax()
    from jax import export

    path = export_path(integrator, adaptive)
    specs = _argument_specs(jax)
    exported = _load_exported(path, jax)
    if exported is not None:
        fn = jax.jit(exported.call)
        try:
            # Compiled here rather than in the first edit, so that an artifact this jaxlib
            # cannot compile is traced anew; the edit's call then finds it compiled (~30 ms
            # with the compilation cache holding it).
            fn.lower(*specs).compile()
            return fn
        except Exception:  # noqa: BLE001  (a cache: traced anew below)
            pass
    traced = _traced_segment_function(integrator, adaptive)
    try:
        exported = export.export(traced, platforms=[jax.default_backend()])(*specs)
    except Exception:  # noqa: BLE001  (not exportable: run it as traced, uncached)
        return traced
    _store_exported(exported, path)
    return jax.jit(exported.call)


def integrate_paths(seeds: np.ndarray, coeffs: np.ndarray, origin: np.ndarray, spacing: float, step: float,
                    max_length: float, integrator: str = "tsit5", rtol: float = 1e-6, atol: float = 1e-9,
                    adaptive: bool = False):
    """Trace every seed's strip downstream and upstream until it stops.

    Parameters
    ----------
    seeds : (k, 2) float64
    coeffs : (G, G, 3) float64
        B-spline coefficients of R_p, R_q and the rim mask (:class:`.field.Raster`).
    origin : (2,) float64
    spacing : float
        The grid's spacing.
    step : float
        Arc length between saved points (drawing units).
    max_length : float
        Longest a strip may grow each way (drawing units).
    integrator : {"tsit5", "kvaerno5"}
    rtol, atol : float
        The PID controller's tolerances (``adaptive`` only).
    adaptive : bool
        diffrax's PID step controller instead of one step per saved point.

    Returns
    -------
    down, up : list of (j_i, 2) float64
        Per seed, the saved points downstream and upstream of it (the seed excluded), in
        order from the seed; a strip that has stopped is cut after its last moving point
        (points closer than step/10 to the one before are its standing still).
    steps : int
        Most steps one strip took in one segment (diagnostics).
    """
    import jax.numpy as jnp

    k = len(seeds)
    fn = _segment_function(integrator, bool(adaptive))
    seg_length = step * SEGMENT
    n_seg = max(int(np.ceil(max_length / seg_length)), 1)
    start = np.concatenate([seeds, seeds]).astype(np.float64)  # downstream, then upstream
    sign = np.concatenate([np.ones(k), -np.ones(k)])
    paths: list[list[np.ndarray]] = [[] for _ in range(2 * k)]
    alive = np.ones(2 * k, bool)
    args = (jnp.asarray(coeffs), jnp.asarray(origin), jnp.asarray(float(spacing)), jnp.asarray(seg_length),
            jnp.asarray(float(rtol)), jnp.asarray(float(atol)))
    most = 0
    for _ in range(n_seg):
        live = np.nonzero(alive)[0]
        if len(live) == 0:
            break
        for b in range(0, len(live), BATCH):
            idx = live[b:b + BATCH]
            y0 = np.empty((BATCH, 2))
            y0[:len(idx)] = start[idx]
            y0[len(idx):] = start[idx[0]]  # padding: copies of a real strip, results dropped
            sg = np.ones(BATCH)
            sg[:len(idx)] = sign[idx]
            ys, n_steps = fn(jnp.asarray(y0), jnp.asarray(sg), *args)
            ys = np.asarray(ys)[:len(idx)]  # (b, SEGMENT, 2)
            most = max(most, int(np.max(np.asarray(n_steps)[:len(idx)])))
            # A strip cut off at MAX_STEPS keeps what it reached: its rows from the first
            # non-finite one on are standing still.
            fin = np.isfinite(ys).all(axis=2)
            upto = np.where(fin.all(axis=1), SEGMENT, np.argmin(fin, axis=1))
            prev = np.concatenate([start[idx][:, None, :], ys[:, :-1]], axis=1)
            moving = (np.linalg.norm(np.nan_to_num(ys - prev), axis=2) >= 0.1 * step) & (np.arange(SEGMENT) < upto[:, None])
            any_moving = moving.any(axis=1)
            last = SEGMENT - 1 - np.argmax(moving[:, ::-1], axis=1)
            for j in np.nonzero(any_moving)[0]:
                i = idx[j]
                paths[i].append(ys[j, :last[j] + 1])
                start[i] = ys[j, last[j]]
            # Still moving at the end of the segment: it goes on; otherwise it stopped here.
            alive[idx] = any_moving & (last == SEGMENT - 1) & (upto == SEGMENT)
    out = [np.concatenate(p) if p else np.zeros((0, 2)) for p in paths]
    return out[:k], out[k:], most


def warm_up(integrator: str = "tsit5", adaptive: bool = False) -> None:
    """Compile the strip integration (~2–3 s the first time ever, ~0.3 s once the exported
    artifact and the compiled code are cached), so the first ``strips`` edit of a session does
    not wait for it."""
    from .field import GRID_SIZE

    coeffs = np.zeros((GRID_SIZE, GRID_SIZE, 3))
    coeffs[:, :, 0] = -1.0  # a uniform flow, mask 0: every strip stops at once
    integrate_paths(np.zeros((1, 2)), coeffs, np.zeros(2), 1.0 / GRID_SIZE, 0.01, 0.01, integrator, adaptive=adaptive)
