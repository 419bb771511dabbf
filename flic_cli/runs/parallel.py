"""Map a function over frames: in this process, in a pool of local processes, or on a dask cluster.

:func:`imap_frames` yields the results as they complete, in any order; callers that need a
deterministic output sort what they collect. Work is handed out lazily (a bounded number of items
in flight), so the memory of the parent stays bounded whatever the number of items.

Workers run single-threaded (BLAS, OpenMP and numba thread pools limited to one thread): the
parallelism is over frames, and nested thread pools would only oversubscribe the cores.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar

from flic_cli.errors import FlicInputError
from flic_cli.runs.environment import THREAD_ENV_VARS, keep_freed_memory

T = TypeVar("T")
R = TypeVar("R")


class SingleThreaded:
    """Picklable wrapper that runs ``func`` with every thread pool limited to one thread.

    Parameters
    ----------
    func : a top-level (picklable) function of one argument.
    """

    def __init__(self, func: Callable[[Any], Any]) -> None:
        self.func = func

    def __call__(self, item: Any) -> Any:
        for name in THREAD_ENV_VARS:  # read by BLAS/OpenMP at import in a fresh worker
            os.environ.setdefault(name, "1")
        keep_freed_memory()
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:  # pragma: no cover - threadpoolctl comes with scikit-learn
            return self.func(item)
        with threadpool_limits(limits=1):
            return self.func(item)


def cpu_cores() -> int:
    """CPU cores this process may run on (at least 1)."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)


def resolve_jobs(jobs: int, items: int | None = None) -> int:
    """``--jobs``: a positive count, or 0 / negative for one process per CPU core; never more
    than the CPU cores nor (when given) the items to process.

    Parameters
    ----------
    jobs : requested number of processes.
    items : the number of items (frames); None = unknown.

    Returns
    -------
    int
        The number of processes, at least 1.
    """
    cores = cpu_cores()
    n = min(jobs, cores) if jobs > 0 else cores
    return max(1, n if items is None else min(n, items))


def jobs_note(jobs: int, items: int) -> str | None:
    """The note the runs print when ``--jobs`` is clamped (:func:`resolve_jobs`), else None."""
    used = resolve_jobs(jobs, items)
    if jobs <= 0 or used >= jobs:
        return None
    return (
        f"note: --jobs {jobs}: using {used} process(es) "
        f"({items} frame(s), {cpu_cores()} CPU core(s))"
    )


class SchedulerError(FlicInputError):
    """The dask scheduler cannot be used (not installed, a malformed address, unreachable)."""


#: ``[protocol://]host:port`` of a dask scheduler (host: a name, IPv4 or [IPv6] address).
_SCHEDULER = re.compile(
    r"(?:(?:tcp|tls|ws|wss|ucx|inproc)://)?(?:[A-Za-z0-9._-]+|\[[0-9A-Fa-f:.]+\]):[0-9]{1,5}"
)


def check_scheduler(address: str | None) -> None:
    """Check a ``--scheduler`` address before any work (None: no scheduler, nothing to check).

    Raises
    ------
    SchedulerError
        When the address is not ``[tcp://]host:port`` (port 1-65535), or dask.distributed is
        not installed.
    """
    if address is None:
        return
    m = _SCHEDULER.fullmatch(address.strip())
    if m is None or not 0 < int(address.rsplit(":", 1)[1]) < 65536:
        raise SchedulerError(
            None,
            f"--scheduler {address!r} is not a dask scheduler address such as "
            "tcp://10.0.0.5:8786 (protocol://host:port)",
        )
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise SchedulerError(
            None,
            "--scheduler needs dask.distributed, which is not installed "
            "(pip install 'flic[distributed]')",
        ) from None


def imap_frames(
    func: Callable[[T], R],
    items: Iterable[T],
    jobs: int = 1,
    scheduler: str | None = None,
) -> Iterator[R]:
    """Apply ``func`` to every item and yield the results as they complete.

    Parameters
    ----------
    func : a top-level (picklable) function of one argument; for ``jobs > 1`` or a scheduler it
        runs in other processes, so it and its argument and result must pickle.
    items : the arguments (e.g. frame references with the run's parameters).
    jobs : processes on this machine: 1 runs everything here, in order; more uses a joblib
        (loky) process pool; 0 or negative: one per CPU core.
    scheduler : address of a dask.distributed scheduler (``tcp://host:8786``); when given, the
        items run on that cluster and ``jobs`` is ignored. Needs ``pip install flic[distributed]``.

    Yields
    ------
    The results, in completion order (the item order when ``jobs == 1``).

    Raises
    ------
    FlicInputError
        When dask.distributed is not installed or the scheduler cannot be reached.
    """
    if scheduler is not None:
        yield from _imap_dask(func, items, scheduler)
        return
    check_scheduler(scheduler)
    jobs = resolve_jobs(jobs)
    if jobs == 1:
        for item in items:
            yield func(item)
        return
    from joblib import Parallel, delayed, parallel_config

    wrapped = SingleThreaded(func)
    with parallel_config(backend="loky", inner_max_num_threads=1):
        results = Parallel(
            n_jobs=jobs, return_as="generator_unordered", pre_dispatch="2*n_jobs", batch_size=1
        )(delayed(wrapped)(item) for item in items)
    yield from results


def _imap_dask(func: Callable[[T], R], items: Iterable[T], scheduler: str) -> Iterator[R]:
    """:func:`imap_frames` on a dask.distributed cluster, a bounded window of tasks in flight."""
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise SchedulerError(
            None,
            "--scheduler needs dask.distributed, which is not installed "
            "(pip install 'flic[distributed]')",
        ) from None
    check_scheduler(scheduler)
    try:
        client = Client(scheduler, timeout="20s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SchedulerError(None, f"cannot reach the dask scheduler {scheduler} ({exc})") from None
    try:
        threads = sum(client.nthreads().values()) or 1
        window = max(4, 2 * threads)
        wrapped = SingleThreaded(func)
        it = iter(items)
        pending = as_completed(loop=client.loop)
        for item in it:
            pending.add(client.submit(wrapped, item, pure=False))
            if pending.count() >= window:
                break
        for future in pending:
            result = future.result()
            future.release()
            yield result
            for item in it:
                pending.add(client.submit(wrapped, item, pure=False))
                break
    finally:
        client.close()
