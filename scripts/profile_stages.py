"""Where the time of one frame goes: read, project, ground, cluster, per-point labels, score.

Times every stage of the per-frame path of ``flic evaluate`` for one method (single thread, after a
warm-up frame) over every selected frame and prints the medians. Run it under a sampling profiler
to see inside a stage: ``py-spy record -f raw -o prof.txt -- python scripts/profile_stages.py``.
The page faults per frame (minor faults: fresh memory the allocator took from the kernel) are
shown because on some virtual machines a fault costs several microseconds.

Usage: python scripts/profile_stages.py [DATA] [--method flic0] [--setting ground] [--repeat 5]
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

from flic_cli.runs.environment import cpu_model, pin_thread_env, thread_limits

pin_thread_env(1)  # before numpy/numba are imported

import numpy as np  # noqa: E402

from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.metrics import score_frame  # noqa: E402
from flic_cli.runs.pipeline import build_segmenter, prepare  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default="../shared/data/semantickitti", type=Path)
    parser.add_argument("--method", default="flic0")
    parser.add_argument("--setting", default="ground")
    parser.add_argument("--ground-remover", default="paper")
    parser.add_argument("--repeat", type=int, default=5, help="passes over the frames")
    parser.add_argument(
        "--keep-freed-memory",
        action="store_true",
        help="tell glibc's malloc to keep freed memory for reuse (mallopt) instead of giving it "
        "back to the kernel and faulting it in again on the next frame",
    )
    args = parser.parse_args()
    if args.keep_freed_memory:
        keep_freed_memory()
    with thread_limits(1):
        run(args)


def keep_freed_memory() -> None:
    """Keep freed memory in the process: no mmap for blocks below 32 MiB, no trimming below
    256 MiB (glibc's ``mallopt``; a no-op elsewhere)."""
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("c")
    if name is None:
        return
    libc = ctypes.CDLL(name)
    if hasattr(libc, "mallopt"):
        m_trim_threshold, m_mmap_threshold = -1, -3
        libc.mallopt(m_mmap_threshold, 32 << 20)
        libc.mallopt(m_trim_threshold, 256 << 20)


def run(args: argparse.Namespace) -> None:
    cfg = load_config()
    ds = open_dataset(args.data)
    seg = build_segmenter(cfg, args.method, args.setting, args.ground_remover)
    stages: dict[str, list[float]] = {}
    faults: dict[str, list[int]] = {}

    def timed(name, func, *a):
        f = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        t = time.perf_counter()
        out = func(*a)
        stages.setdefault(name, []).append(1e3 * (time.perf_counter() - t))
        faults.setdefault(name, []).append(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f)
        return out

    refs = ds.refs()
    for i in range(args.repeat * len(refs) + 1):
        ref = refs[max(i - 1, 0) % len(refs)]
        frame = timed("read", ds.load, ref)
        prep = timed("project", prepare, frame, args.setting, cfg.projection)
        ground = timed("ground", seg.ground_step, prep.image, prep.points)
        labels = timed("cluster+labels", seg.cluster, prep.image, prep.points, ground)
        if prep.labels is not None:  # matches and segmentation statistics, as evaluate does
            timed("score", score_frame, prep.labels, labels, prep.points)
        if i == 0:  # warm-up frame (JIT cache load)
            stages.clear()
            faults.clear()
    total = sum(np.median(v) for v in stages.values())
    print(
        f"{args.method}, {args.setting} setting, {len(refs)} frames x {args.repeat}, "
        f"one thread of {cpu_model()}:"
    )
    for name, v in stages.items():
        med = np.median(v)
        print(
            f"  {name:15s} median {med:7.3f} ms  ({100 * med / total:4.1f} %)  "
            f"{np.mean(faults[name]):6.1f} page faults per frame"
        )
    print(f"  {'total':15s} median {total:7.3f} ms  -> {1e3 / total:.1f} frames/s on one core")


if __name__ == "__main__":
    main()
