"""The engine that runs batch and dataset jobs: a Dask cluster.

By default a local cluster of worker processes on this machine (one per core, one thread
each), made when the run starts and closed when it ends; with a scheduler address, the workers
of an existing dask.distributed cluster. Either way the jobs are the same functions
(:mod:`sketchforge.batch.jobs`), sent their inputs as bytes, so the outputs are the same bytes.

Workers are processes that live for the whole run: imports, the plugin host and compiled JAX
functions stay warm from one job to the next. Jobs are handed out a few per worker at a time,
so a run of 10,000 documents never holds more than a few of them in memory.
"""

from __future__ import annotations

import logging
import os
import uuid
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from sketchforge.errors import SketchforgeError, quote

#: Jobs in flight per worker: enough to keep each busy while results travel back.
IN_FLIGHT_PER_WORKER = 2
#: Seconds to wait for a scheduler to answer, and for its first worker.
CONNECT_TIMEOUT = 20
#: A job whose worker died this many times is given up (a native crash that repeats).
ALLOWED_FAILURES = 1


class WorkerDied(SketchforgeError):
    """A job's worker process died while running it (a native crash, or out of memory)."""


def local_cores() -> int:
    """Cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


class Engine:
    """A Dask client for sketchforge jobs; use as a context manager.

    Parameters
    ----------
    scheduler : str or None
        ``tcp://HOST:PORT`` of a running dask.distributed scheduler; None starts a local
        cluster.
    workers : int or None
        Worker processes of the local cluster (None: one per core); only without
        ``scheduler``.
    timeout : float
        Seconds to wait for the scheduler to answer, and then for its first worker.
    """

    def __init__(self, scheduler: str | None = None, workers: int | None = None, timeout: float = CONNECT_TIMEOUT) -> None:
        if scheduler is not None and workers is not None:
            raise SketchforgeError("--workers sets the size of the local cluster; with --scheduler the cluster's own workers run the jobs")
        if workers is not None and workers < 1:
            raise SketchforgeError(f"--workers must be at least 1, got {workers}")
        self.scheduler = scheduler
        self.requested = workers
        self.timeout = timeout
        self._cluster: Any = None
        self._client: Any = None

    # --- life cycle ----------------------------------------------------------------------------
    def __enter__(self) -> Engine:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def start(self) -> None:
        """Connect (or start the local cluster), then check every worker runs the same
        software as this process and warm it up."""
        import dask
        from dask.distributed import Client, LocalCluster

        from sketchforge.batch.jobs import software, software_difference, warm_up

        # Dask's own log lines (a slow event loop, a closing comm, a task given up after its
        # worker died) would come between ours: each of those reaches the user as a result,
        # and so as one line from here.
        logging.getLogger("distributed").setLevel(logging.CRITICAL)
        if self.scheduler is None:
            # A worker gets a new job only when its thread is free: when it dies, only the job
            # it was running is lost (with queued ones, they would be counted as its victims).
            local = {"distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
                     "distributed.scheduler.worker-saturation": 1.0}
            try:
                with dask.config.set(local):
                    self._cluster = LocalCluster(
                        n_workers=self.requested or local_cores(),
                        threads_per_worker=1,
                        processes=True,
                        host="127.0.0.1",
                        scheduler_port=0,
                        # The scheduler always serves HTTP: on a free loopback port, not
                        # on 8787 (with a warning line when another cluster holds it).
                        dashboard_address="127.0.0.1:0",
                        silence_logs=logging.CRITICAL,
                    )
                self._client = Client(self._cluster)
            except (OSError, RuntimeError, TimeoutError) as exc:  # no port, no process could start
                self.close()
                raise SketchforgeError(f"cannot start a local Dask cluster: {type(exc).__name__}: {exc}") from None
        else:
            try:
                self._client = Client(self.scheduler, timeout=f"{self.timeout}s")
            except (OSError, TimeoutError, ValueError) as exc:
                raise SketchforgeError(f"cannot reach the Dask scheduler at {quote(self.scheduler)}: {exc}") from None
            try:
                self._client.wait_for_workers(1, timeout=self.timeout)
            except (TimeoutError, OSError):
                self.close()
                raise SketchforgeError(
                    f"the Dask scheduler at {quote(self.scheduler)} has no worker after {self.timeout:g} s; "
                    f"start some with `dask worker {self.scheduler} --nthreads 1`"
                ) from None
        mine = software()
        try:
            theirs = self._client.run(software)
            self._client.run(warm_up)
        except Exception as exc:  # noqa: BLE001 - a worker that cannot even import sketchforge
            self.close()
            raise SketchforgeError(f"a Dask worker cannot run sketchforge: {type(exc).__name__}: {exc}") from None
        for address, soft in sorted(theirs.items()):
            diff = software_difference(mine, tuple(tuple(x) for x in soft))
            if diff is not None:
                self.close()
                raise SketchforgeError(
                    f"Dask worker {address} runs other software than this machine ({diff}): its outputs could "
                    "differ; install the same versions on every worker"
                )

    def wait_for_workers(self, n: int, timeout: float | None = None) -> None:
        """Wait until ``n`` workers are connected (workers of a cluster join one by one)."""
        if self._client is None:
            raise RuntimeError("the engine is not started")
        try:
            self._client.wait_for_workers(n, timeout=self.timeout if timeout is None else timeout)
        except (TimeoutError, OSError):
            raise SketchforgeError(f"{self.where}: fewer than {n} workers after {timeout or self.timeout:g} s") from None

    def close(self) -> None:
        """Close the client and, when it was made here, the local cluster."""
        for thing in (self._client, self._cluster):
            if thing is not None:
                try:
                    thing.close()
                except Exception:  # noqa: BLE001 - closing is best effort (a dead scheduler)
                    pass
        self._client = self._cluster = None

    # --- running jobs --------------------------------------------------------------------------
    @property
    def workers(self) -> int:
        """Workers connected now."""
        if self._client is None:
            return 0
        return len(self._client.scheduler_info(n_workers=-1).get("workers", {}))

    @property
    def where(self) -> str:
        """The cluster in words: 'a local cluster of 2 workers' or the scheduler's address."""
        n = self.workers
        workers = f"{n} worker" + ("" if n == 1 else "s")
        if self.scheduler is None:
            return f"a local Dask cluster of {workers}"
        return f"the Dask cluster at {self.scheduler} ({workers})"

    def run(
        self, fn: Callable[..., Any], jobs: Iterable[tuple[Any, tuple]], window: int | None = None
    ) -> Iterator[tuple[Any, Any]]:
        """Run ``fn(*args)`` for each ``(tag, args)`` of ``jobs``, yielding ``(tag, result)`` in
        the order the jobs finish; a job whose worker died yields a :class:`WorkerDied` as its
        result instead. ``jobs`` is read lazily: at most ``window`` jobs (default a few per
        worker) are in flight, so inputs are read just before they are sent."""
        from dask.distributed import as_completed

        if self._client is None:
            raise RuntimeError("the engine is not started")
        window = window or max(2, IN_FLIGHT_PER_WORKER * max(1, self.workers))
        run_id = uuid.uuid4().hex[:12]
        source = iter(jobs)
        pending = as_completed(loop=self._client.loop)
        tags: dict[str, Any] = {}
        count = 0

        def submit_next() -> bool:
            nonlocal count
            try:
                tag, args = next(source)
            except StopIteration:
                return False
            # Unique on a shared scheduler, and never equal to an earlier job's (Dask would
            # hand back that job's result).
            key = f"sketchforge-{fn.__name__}-{run_id}-{count}"
            count += 1
            future = self._client.submit(fn, *args, key=key, pure=False, retries=0)
            tags[future.key] = tag
            pending.add(future)
            return True

        for _ in range(window):
            if not submit_next():
                break
        try:
            for future in pending:
                tag = tags.pop(future.key)
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001 - KilledWorker, a lost connection
                    result = WorkerDied(_died(exc))
                future.release()
                submit_next()
                yield tag, result
        finally:
            for future in list(pending.futures):
                future.cancel()


def _died(exc: BaseException) -> str:
    name = type(exc).__name__
    if name == "KilledWorker":
        return "its worker process died while running it (a native crash, or out of memory)"
    return f"the cluster lost it: {name}: {' '.join(str(exc).split())}"
