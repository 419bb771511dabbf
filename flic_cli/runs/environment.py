"""What a timing depends on: thread pools, CPU, library versions.

:func:`pin_thread_env` must run before numpy or scipy are imported (the thread pools of OpenMP,
OpenBLAS and MKL read these variables once, at import); :func:`thread_limits` then
enforces the limit at run time as well (``numba.set_num_threads`` and ``threadpoolctl``), which
also covers a process that imported numpy earlier. :func:`collect_environment` records what was
in effect.

This module imports nothing heavy at module level: the CLI calls :func:`pin_thread_env` first.
"""

from __future__ import annotations

import functools
import os
import platform
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import datetime, timezone
from importlib import metadata
from typing import Any

#: Environment variables that size the thread pools of OpenMP and the BLAS libraries. numba's
#: pool is sized at run time only (``numba.set_num_threads``): changing ``NUMBA_NUM_THREADS`` in a
#: process that has imported numba makes its next compilation fail, and flic's kernels are serial.
THREAD_ENV_VARS = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
    "PARLAY_NUM_THREADS",  # the `dbscan` package (DBSCAN backend "fastdbscan")
)

#: Distributions whose versions go into the record (import name -> distribution name).
_VERSIONED = {
    "flic": "flic",
    "numpy": "numpy",
    "scipy": "scipy",
    "numba": "numba",
    "llvmlite": "llvmlite",
    "sklearn": "scikit-learn",
    "pandas": "pandas",
    "threadpoolctl": "threadpoolctl",
}


def pin_thread_env(threads: int) -> dict[str, str]:
    """Set the thread-pool environment variables to ``threads`` (before heavy imports).

    Parameters
    ----------
    threads : threads per pool, >= 1.

    Returns
    -------
    dict
        The variables as set.
    """
    value = str(int(threads))
    for name in THREAD_ENV_VARS:
        os.environ[name] = value
    return {name: os.environ[name] for name in THREAD_ENV_VARS if name in os.environ}


@functools.cache
def keep_freed_memory() -> bool:
    """Ask glibc to keep freed memory for reuse instead of returning it to the kernel.

    flic allocates and frees the same few megabytes for every frame; when glibc hands them back
    (large blocks are mmapped and unmapped, the heap is trimmed), the next frame faults every page
    in again, 2-10 us each: the measured cost was tens of page faults per frame and occasional
    spikes (one Moosmann image build 0.50 ms with 235 faults, 0.09 ms once memory was kept). This
    raises glibc's mmap and trim thresholds (``mallopt``); it is a no-op elsewhere.

    Returns
    -------
    bool
        Whether the setting was applied.
    """
    import ctypes

    try:
        libc = ctypes.CDLL(None)  # the running program's symbols: libc's on Linux
    except OSError:  # pragma: no cover
        return False
    if not hasattr(libc, "mallopt"):
        return False
    m_trim_threshold, m_mmap_threshold = -1, -3
    ok = libc.mallopt(m_mmap_threshold, 32 << 20) == 1
    return bool(libc.mallopt(m_trim_threshold, 256 << 20) == 1 and ok)


@contextmanager
def thread_limits(threads: int) -> Iterator[dict[str, Any]]:
    """Limit numba's and the native libraries' thread pools to ``threads`` inside the block.

    Yields
    ------
    dict
        What is in effect: ``requested``, ``numba`` (``numba.get_num_threads()``), ``numba_max``
        (``numba.config.NUMBA_NUM_THREADS``), ``threadpoolctl`` (True when it is installed and
        applied), ``pools`` (one entry per native pool: library, API, threads, version) and
        ``env`` (the thread environment variables).
    """
    import numba

    numba_max = int(numba.config.NUMBA_NUM_THREADS)
    previous = numba.get_num_threads()
    numba.set_num_threads(max(1, min(int(threads), numba_max)))
    try:
        from threadpoolctl import threadpool_info, threadpool_limits
    except ImportError:  # pragma: no cover - threadpoolctl comes with scikit-learn
        threadpool_info = threadpool_limits = None
    info: dict[str, Any] = {
        "requested": int(threads),
        "numba": numba.get_num_threads(),
        "numba_max": numba_max,
        "numba_threading_layer": str(numba.config.THREADING_LAYER),
        "threadpoolctl": threadpool_limits is not None,
        "pools": [],
        "env": {name: os.environ.get(name) for name in THREAD_ENV_VARS},
    }
    try:
        if threadpool_limits is None:
            yield info
            return
        with threadpool_limits(limits=int(threads)):
            info["pools"] = [
                {
                    "library": pool.get("prefix"),
                    "api": pool.get("internal_api"),
                    "threads": pool.get("num_threads"),
                    "version": pool.get("version"),
                }
                for pool in threadpool_info()
            ]
            yield info
    finally:
        numba.set_num_threads(min(previous, numba_max))


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else :func:`platform.processor`)."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key.strip() in ("model name", "Hardware", "cpu model") and value.strip():
                    return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def _version(dist: str) -> str | None:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return None


def collect_environment(threads: dict[str, Any] | None = None, **extra: Any) -> dict[str, Any]:
    """A JSON-ready record of the machine, the interpreter, the libraries and the thread pools.

    Parameters
    ----------
    threads : what :func:`thread_limits` yielded (None: not recorded).
    **extra : further keys (the run's parameters), added as they are.

    Returns
    -------
    dict
        Keys ``cpu``, ``cores_logical``, ``cores_available``, ``machine``, ``platform``,
        ``python``, ``python_implementation``, ``versions``, ``threads``, ``command``, ``date``,
        then ``extra``.
    """
    try:
        available = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # not on Linux
        available = os.cpu_count()
    env: dict[str, Any] = {
        "cpu": cpu_model(),
        "cores_logical": os.cpu_count(),
        "cores_available": available,
        "machine": platform.machine(),
        "platform": platform.platform(),
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "versions": {name: _version(dist) for name, dist in _VERSIONED.items()},
        "threads": threads,
        "command": " ".join([os.path.basename(sys.argv[0]), *sys.argv[1:]]),
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
    }
    env.update(extra)
    return env


def environment_line(env: dict[str, Any]) -> str:
    """One line for the terminal: CPU, cores, Python, library versions, threads in effect."""
    v = env.get("versions", {})
    threads = env.get("threads") or {}
    pools = threads.get("pools") or []
    blas = ",".join(sorted({str(p["threads"]) for p in pools})) or "n/a"
    return (
        f"{env.get('cpu')} ({env.get('cores_available')}/{env.get('cores_logical')} cores), "
        f"Python {env.get('python')}, numpy {v.get('numpy')}, scipy {v.get('scipy')}, "
        f"numba {v.get('numba')}, scikit-learn {v.get('sklearn')}; "
        f"threads: numba {threads.get('numba')}, native pools {blas}"
    )
