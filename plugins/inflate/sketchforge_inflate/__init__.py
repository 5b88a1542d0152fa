"""Inflate a drawn contour into a smooth, faired height-field mesh (thesis 3.2, 4.2).

The hook implementation is in :mod:`sketchforge_inflate.plugin`; the pipeline and its
parameters (units of the smoothing weight α) in :mod:`sketchforge_inflate.inflate`.
"""

from sketchforge_inflate.inflate import DEFAULT_PARAMS, SMOOTHING_UNITS_PER_SIZE, inflate_stroke, validate_params

__all__ = ["DEFAULT_PARAMS", "SMOOTHING_UNITS_PER_SIZE", "inflate_stroke", "validate_params"]
