"""Where the time of Bogoslavskyi's ground remover goes, frame by frame.

For the given frames of a log: valid pixels, the share of pixels the growth labels as ground, and
the median time over ``--calls`` calls each (one thread) of its three calls: the in-painting with
the legs of the angles, the arctangents, and the smoothing with the growth and shift. The
growth's cost follows the ground it reaches, so this shows whether a frame is slow because of
its content or because of the machine.

Usage: python scripts/bogoslavskyi_growth.py DATA --frames 2,28,101,250 [--sequence 08] [--calls 50]

DATA is a Moosmann log or a SemanticKITTI root (then ``--sequence`` picks the sequence). With
``PYTHONPATH`` pointing at another checkout's tree the same script times that version.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from flic_cli.config import load_config
from flic_cli.ground.bogoslavskyi import (
    BogoslavskyiGround,
    _repair_and_legs,
    _row_trig,
    _smooth_grow_shift,
    savgol_kernel,
)
from flic_cli.io import open_dataset
from flic_cli.runs.environment import thread_limits
from flic_cli.runs.pipeline import prepare


def _median_ms(fn, calls: int) -> float:
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1000.0 * float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path)
    parser.add_argument("--frames", required=True, help="comma-separated frame numbers")
    parser.add_argument("--calls", type=int, default=50)
    parser.add_argument("--sequence", default=None, help="SemanticKITTI sequence")
    args = parser.parse_args()
    with thread_limits(1):
        run(args.log, [int(f) for f in args.frames.split(",")], args.calls, args.sequence)


def run(log: Path, frames: list[int], calls: int, sequence: str | None) -> None:
    cfg = load_config()
    ds = open_dataset(log, [sequence] if sequence else None)
    refs = {ref.frame: ref for ref in ds.refs()}
    remover = BogoslavskyiGround()
    kernel = savgol_kernel(remover.window)
    threshold = float(np.float32(np.radians(remover.angle_deg)))
    start = float(np.radians(remover.start_angle_deg))
    print("frame,valid_share,ground_share,inpainting_and_legs_ms,arctan2_ms,growth_ms")
    for frame in frames:
        image = prepare(ds.load(refs[frame]), "ground", cfg.projection).image
        ranges = np.ascontiguousarray(image.ranges, dtype=np.float32)
        sin_p, cos_p = _row_trig(image.elevation)
        depth, dy, dx = _repair_and_legs(ranges, sin_p, cos_p)
        angle = np.arctan2(dy, dx)
        ground = _smooth_grow_shift(ranges, depth, angle, kernel, threshold, start)  # compiles
        legs = _median_ms(lambda r=ranges, s=sin_p, c=cos_p: _repair_and_legs(r, s, c), calls)
        atan = _median_ms(lambda y=dy, x=dx: np.arctan2(y, x), calls)
        grow = _median_ms(
            lambda r=ranges, d=depth, a=angle: _smooth_grow_shift(
                r, d, a, kernel, threshold, start
            ),
            calls,
        )
        valid = float((ranges > 0).mean())
        print(f"{frame},{valid:.3f},{float(ground.mean()):.3f},{legs:.3f},{atan:.3f},{grow:.3f}")


if __name__ == "__main__":
    main()
