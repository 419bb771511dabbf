"""Time one method's ``segment`` in several checkouts on the same images, processes alternated.

``flic benchmark`` of two revisions (``scripts/benchmark_revisions.py``) times every stage of
the pipeline and, on the 2-core machine shared with other jobs, cannot resolve 10-20 %
(results/benchmark/revisions/README.md). This script times only the method: the current
checkout projects the frames once (no-ground setting, the paper's "No Ground" column) and
saves the images; every checkout named on the command line then runs in a process of its own
(its ``.venv``, its ``flic_cli`` first on the path), builds the same method with the same
parameters and times ``segment`` on those images. The processes stay up; one pass over all
frames (``--repeat`` calls each, the fastest kept) goes to each in turn, the order reversed
every round (ABBA), all on one core (``taskset -c CPU``, ``NUMBA_NUM_THREADS=1``). The
allocator's mmap threshold is fixed (``MALLOC_MMAP_THRESHOLD_``, ``MALLOC_TRIM_THRESHOLD_``,
``MALLOC_TOP_PAD_``) unless ``--default-malloc``: otherwise every call's large arrays may come
from fresh pages, whose faults cost about as much as the clustering itself here and vary with
the machine's load and each process's history. Name a checkout twice for an A/A control::

    python scripts/kernel_revisions.py --data ../shared/data/semantickitti \\
        --method flic_cli.methods.bridge:Bridge --rounds 20 --repeat 3 \\
        before=/work/base after=. after2=.

Printed per checkout: the median over the frames of the per-frame minimum (and median) over
the rounds, in ms, and the median over the frames of their ratio to the first checkout's.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

WORKER = r"""
import gc, importlib, json, sys, time
import numpy as np
from flic_cli.range_image import RangeImage
z = np.load(sys.argv[1])
module, name = sys.argv[2].split(":")
method = getattr(importlib.import_module(module), name)(**json.loads(sys.argv[3]))
frames = []
for k in range(int(z["n"])):
    img = RangeImage(z[f"r{k}"], z[f"e{k}"], z[f"p{k}"], "rings", counts=z[f"c{k}"])
    frames.append((img, z[f"x{k}"]))
for img, pts in frames[:3]:
    method.segment(img, pts, None)
print(json.dumps([int(method.segment(img, pts, None).max()) for img, pts in frames]), flush=True)
for line in sys.stdin:
    repeat, out = int(line), []
    gc.disable()
    for img, pts in frames:
        best = 1 << 62
        for _ in range(repeat):
            t = time.perf_counter_ns()
            method.segment(img, pts, None)
            best = min(best, time.perf_counter_ns() - t)
        out.append(best)
    gc.enable()
    print(json.dumps(out), flush=True)
"""

MALLOC = {
    "MALLOC_MMAP_THRESHOLD_": "268435456",
    "MALLOC_TRIM_THRESHOLD_": "268435456",
    "MALLOC_TOP_PAD_": "67108864",
}


def save_frames(data: Path, out: Path) -> int:
    """Project every frame of ``data`` (no-ground setting, the default projection) with the
    current checkout and save ranges, elevations, point pixels, counts and points to ``out``
    (npz); returns the number of frames."""
    from flic_cli.config.parser import load_config
    from flic_cli.io import open_dataset
    from flic_cli.runs.pipeline import prepare
    from flic_cli.sensor_params import for_dataset

    ds = open_dataset(data, require_labels=True)
    refs = ds.refs()
    projection = for_dataset(load_config(), ds, refs).projection
    arrays: dict[str, np.ndarray] = {}
    for k, ref in enumerate(refs):
        prep = prepare(ds.load(ref), "no-ground", projection)
        im = prep.image
        if im.projection != "rings" or im.has_azimuth_offset or not im.every_point_has_pixel:
            raise SystemExit(f"{ref}: not a ring image with every point in a pixel")
        arrays |= {f"r{k}": im.ranges, f"e{k}": im.elevation, f"p{k}": im.point_pixel}
        arrays |= {f"c{k}": im.point_counts(), f"x{k}": prep.points}
    np.savez(out, n=len(refs), **arrays)
    return len(refs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("checkouts", nargs="+", help="NAME=ROOT (a checkout with a .venv)")
    ap.add_argument("--data", type=Path, required=True, help="a labelled SemanticKITTI root")
    ap.add_argument("--method", required=True, help="module:Class of a Method")
    ap.add_argument("--params", default="{}", help="the method's parameters, JSON")
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--repeat", type=int, default=3, help="calls per frame and pass (min kept)")
    ap.add_argument("--cpu", type=int, default=1)
    ap.add_argument("--default-malloc", action="store_true", help="leave the allocator alone")
    args = ap.parse_args()
    named = [c.split("=", 1) for c in args.checkouts]
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    if not args.default_malloc:
        env |= MALLOC
    with tempfile.TemporaryDirectory() as tmp:
        frames = Path(tmp) / "frames.npz"
        n = save_frames(args.data, frames)
        procs, clusters = {}, {}
        for name, root in named:
            root = str(Path(root).resolve())
            cmd = ["taskset", "-c", str(args.cpu), f"{root}/.venv/bin/python", "-c", WORKER]
            cmd += [str(frames), args.method, args.params]
            p = subprocess.Popen(
                cmd, cwd=root, env=env | {"PYTHONPATH": root}, stdin=subprocess.PIPE,
                stdout=subprocess.PIPE, text=True,
            )  # fmt: skip
            procs[name] = p
            clusters[name] = json.loads(p.stdout.readline())
        times: dict[str, list[list[int]]] = {name: [] for name in procs}
        for r in range(args.rounds):
            for name in list(procs) if r % 2 == 0 else list(procs)[::-1]:
                procs[name].stdin.write(f"{args.repeat}\n")
                procs[name].stdin.flush()
                times[name].append(json.loads(procs[name].stdout.readline()))
        for p in procs.values():
            p.stdin.close()
            p.wait()
    ms = {name: np.array(t) / 1e6 for name, t in times.items()}  # rounds x frames
    first = named[0][0]
    print(f"{n} frames, {args.rounds} rounds x {args.repeat} calls, cpu {args.cpu}, {args.method}")
    for name, a in ms.items():
        same = "same clusters" if clusters[name] == clusters[first] else "OTHER CLUSTERS"
        fmin, fmed = a.min(axis=0), np.median(a, axis=0)
        rmin = np.median(fmin / ms[first].min(axis=0))
        rmed = np.median(fmed / np.median(ms[first], axis=0))
        print(
            f"{name:10s} min {np.median(fmin):.4f} ms  median {np.median(fmed):.4f} ms  "
            f"/ {first}: min {rmin:.3f}  median {rmed:.3f}  ({same})"
        )
    sys.stdout.flush()


if __name__ == "__main__":
    main()
