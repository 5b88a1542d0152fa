"""The built-in (``poisson``) inflater's parameters: their defaults and validation (its
``check_params``). Other inflaters have their own; the document never reads these keys."""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from types import MappingProxyType

from sketchforge.errors import ParameterError

#: ``resolution``: target edge length in drawing units; ``inflation``: height scale (1 turns a
#: disk of radius R into a hemisphere); ``smoothing``: fairing weight α in [0, 1), 0 = none
#: (its length unit is tied to the shape's size, see plugins/inflate).
DEFAULT_INFLATE_PARAMS: Mapping[str, float] = MappingProxyType({"resolution": 0.03, "inflation": 1.0, "smoothing": 0.5})


#: Upper bound of resolution and inflation: the drawing's coordinate range (±1e9), beyond
#: which heights and areas overflow.
MAX_PARAM = 1e9


def check_inflate_params(params: Mapping | None) -> dict:
    """Defaults filled in, values checked, unknown keys refused.

    Returns
    -------
    dict with float ``resolution`` > 0, ``inflation`` >= 0, ``smoothing`` in [0, 1).

    Raises
    ------
    ParameterError
        With a message naming the parameter and the allowed range.
    """
    out = dict(DEFAULT_INFLATE_PARAMS)
    if params is not None:
        if not isinstance(params, Mapping):
            raise ParameterError(f"inflation parameters must be a mapping, got {type(params).__name__}")
        unknown = sorted(str(k) for k in params if k not in DEFAULT_INFLATE_PARAMS)
        if unknown:
            raise ParameterError(f"unknown inflation parameter {unknown[0][:60]!r} (known: {', '.join(DEFAULT_INFLATE_PARAMS)})")
        for key in DEFAULT_INFLATE_PARAMS:
            if key in params:
                v = params[key]
                if isinstance(v, bool) or not isinstance(v, numbers.Real):
                    raise ParameterError(f"inflation parameter {key!r} must be a number, got {v!r}")
                try:
                    out[key] = float(v)
                except OverflowError:
                    raise ParameterError(f"inflation parameter {key!r} is too large for a number") from None
    for key, v in out.items():
        if not math.isfinite(v):
            raise ParameterError(f"inflation parameter {key!r} must be a finite number, got {v}")
    if out["resolution"] <= 0:
        raise ParameterError(f"resolution (target edge length) must be > 0, got {out['resolution']}")
    if out["resolution"] > MAX_PARAM:
        raise ParameterError(f"resolution (target edge length) must be at most {MAX_PARAM:.0e}, got {out['resolution']:.3g}")
    if out["inflation"] < 0:
        raise ParameterError(f"inflation must be >= 0, got {out['inflation']}")
    if out["inflation"] > MAX_PARAM:
        raise ParameterError(f"inflation must be at most {MAX_PARAM:.0e}, got {out['inflation']:.3g}")
    if not 0.0 <= out["smoothing"] < 1.0:
        raise ParameterError(f"smoothing (fairing weight α) must be in [0, 1), got {out['smoothing']}")
    return out
