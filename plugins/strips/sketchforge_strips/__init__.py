"""The thesis' strip method as a sculpt solver (``"solver": "strips"``), thesis 4.3–4.6.

:mod:`.regions`   seeds on the stroke, base characteristics through them: S•, B•*, M• (4.3)
:mod:`.field`     the per-vertex fields the strips read, as C² grid B-splines (smooth enough
                  for adaptive solvers)
:mod:`.integrate` the strips, integrated with diffrax (Tsit5 or Kvaerno5), jitted and vmapped
:mod:`.reconstruct` heights at the vertices by multiquadric RBF (4.6)
:mod:`.solver`    the solve, :data:`.solver.STRIPS` the registered value

Importing this package imports neither JAX nor diffrax; the solve does, on first use.
"""
