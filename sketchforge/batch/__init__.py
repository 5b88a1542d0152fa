"""Headless work at scale: ``sketchforge batch`` (replay and export many documents) and
``sketchforge dataset`` (random samples for learning shape from shading), both on a Dask
cluster (:mod:`.engine`: a local one by default, or an existing dask.distributed cluster).

- :mod:`.jobs`: what a worker runs (bytes in, bytes out);
- :mod:`.engine`: the Dask cluster, warm workers, jobs handed out a few at a time;
- :mod:`.batch`: finding documents, naming outputs, writing them and the report;
- :mod:`.samples`, :mod:`.dataset`: the random samples and their files;
- :mod:`.progress`: the progress bar; :mod:`.cli`: the two subcommands.
"""
