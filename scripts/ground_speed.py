"""Time the ground removers alone, interleaved frame by frame, on one data set.

Every frame is read and projected once; then each round calls every remover once per frame, in
turn (the order turns from frame to frame, since the first call on a frame finds it out of
cache), so that all removers see the same machine load. Prints (and optionally writes) the median,
p5 and p95 milliseconds per frame and each remover's median relative to the first one. Removers
that need points get the frame's points. Timings on a shared machine are noisy: compare the
relative figures of one run, not absolute figures across runs.

Each call is what the ground table (``scripts/ground_table.py``) and the runs time:
``remover.extract(image, points)``, the remover's whole decision (its mask, its per-point decision
such as step 7 of ``column``, and the image the clusterers see). A remover is a registered name,
optionally with parameters separated by ``;`` (``column:hidden_points=False``,
``column:neighbour_px=0;under_m=1.0``).

Usage::

    python scripts/ground_speed.py ../shared/data/semantickitti \\
        --removers column,paper,bogoslavskyi,patchworkpp --rounds 3 \\
        --out results/ground/speed_per_point_semantickitti.csv
"""

from __future__ import annotations

import argparse
import ast
import gc
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import prepare


def make_remover(cfg, spec: str):
    """A remover from ``NAME`` or ``NAME:param=value;...`` (the registered remover with those
    parameters changed)."""
    name, _, params = spec.partition(":")
    remover = cfg.remover(name)
    if params:
        kw = {k: ast.literal_eval(v) for k, v in (p.split("=") for p in params.split(";"))}
        remover = type(remover)(**{**remover.__dict__, **kw})
    return remover


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--removers", default="paper,column,bogoslavskyi")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=None, help="first N frames only")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()

    names = args.removers.split(",")
    cfg = load_config()
    ds = open_dataset(args.data)
    frames = [prepare(ds.load(ref), "ground", cfg.projection) for ref in ds.refs()[: args.frames]]
    removers = {n: make_remover(cfg, n) for n in names}
    calls = {n: r.extract for n, r in removers.items()}
    for call in calls.values():  # warm-up: JIT compilation or cache load
        call(frames[0].image, frames[0].points)
    times: dict[str, list[float]] = {n: [] for n in names}
    gc.collect()
    gc.disable()
    order = list(calls.items())
    for k in range(args.rounds):
        for i, prep in enumerate(frames):
            # the order turns from frame to frame: the first remover after a new frame finds it
            # out of cache, the others in it
            turn = (i + k) % len(order)
            for n, remover in order[turn:] + order[:turn]:
                t0 = time.perf_counter()
                remover(prep.image, prep.points)
                times[n].append(time.perf_counter() - t0)
    gc.enable()
    h, w = frames[0].image.ranges.shape
    base = float(np.median(times[names[0]]))
    df = pd.DataFrame(
        [
            {
                "remover": n,
                "image": f"{w}x{h}",
                "calls": len(t),
                "median_ms": round(1000 * float(np.median(t)), 4),
                "p5_ms": round(1000 * float(np.percentile(t, 5)), 4),
                "p95_ms": round(1000 * float(np.percentile(t, 95)), 4),
                f"median_vs_{names[0]}": round(float(np.median(t)) / base, 2),
            }
            for n, t in times.items()
        ]
    )
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
