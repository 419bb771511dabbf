"""The column ground step of 3e00d28 against this tree's, in one process, alternated per frame.

``flic benchmark`` across revisions (``scripts/benchmark_revisions.py``) runs two processes, and
on the shared 2-core machine their ratios stray by 10-20 % (``results/benchmark/revisions/``).
This script compiles 3e00d28's ``flic_cli/ground/column.py`` from a checkout of it (its one
import that moved since patched, numba's disk cache off) next to this tree's, and on every frame
calls both revisions' column remover on the same range image, alternating, ``--repeat`` times
each; it first checks that both give the same ground mask, held cells, per-point decision and
attachments. The run-limit cache (:func:`flic_cli.sensor_params.column_run_jumps`) is cleared
before each call of this tree's remover, as on SemanticKITTI, whose rows' elevations differ per
frame, so a repeated call finds nothing cached::

    taskset -c 1 env NUMBA_NUM_THREADS=1 python scripts/column_step_ab.py /work/base \
        --data ../shared/data/semantickitti

Prints, for the whole step (3e00d28: ``ColumnGround.split`` and ``point_ground`` and the
attachments' point counts, as its ``extract_ground`` did; this tree: ``ColumnGround.extract``)
and for the kernel alone (``_column_ground``), the median over frames of each revision's fastest
call (microseconds) and the median and range over frames of the per-frame ratio this / 3e00d28.
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from flic_cli.config import load_config
from flic_cli.ground import column
from flic_cli.io import open_dataset
from flic_cli.runs.pipeline import Prepared, prepare
from flic_cli.sensor_params import _run_jumps

#: 3e00d28's column parameters in the order of its ``_param_vector``.
KEYS = (
    "sensor_height_m", "noise_m", "slope_change_deg", "kerb_m", "max_step_m", "flat_deg",
    "seed_tolerance_m", "base_band_m", "neighbour_px", "neighbour_band_m", "foot_deg", "under_m",
    "attach_m", "face_deg",
)  # fmt: skip


def load_before(checkout: Path) -> types.ModuleType:
    """3e00d28's ``flic_cli/ground/column.py`` as a module of its own (``before_column``)."""
    src = (checkout / "flic_cli/ground/column.py").read_text()
    src = src.replace("from flic_cli.config.component import", "from flic_cli.component import")
    src = src.replace("cache=True", "cache=False")
    mod = types.ModuleType("before_column")
    mod.__file__ = str(checkout / "flic_cli/ground/column.py")
    sys.modules[mod.__name__] = mod
    exec(compile(src, mod.__file__, "exec"), mod.__dict__)  # noqa: S102 (the before checkout)
    return mod


def before_step(old: Any, p: Prepared) -> tuple:
    """3e00d28's ground step: mask, held cells and attachments, per-point decision, and the
    attachments' point counts read from the image the clusterers see (its ``extract_ground``)."""
    mask, held, attached = old.split(p.image, p.points)
    per_point = old.point_ground(p.image, p.points, mask)
    decided, clustered = (None, p.image) if per_point is None else per_point
    if attached is not None and len(attached) and clustered is not p.image:
        attached = attached.copy()
        attached[:, 2] = clustered.point_counts().reshape(-1)[attached[:, 0]]
    return mask, held, decided, attached


def after_step(new: column.ColumnGround, p: Prepared) -> Any:
    """This tree's ground step, its run-limit cache emptied first (every frame misses it on
    SemanticKITTI)."""
    _run_jumps.cache_clear()
    return new.extract(p.image, p.points)


def alternate(a: Callable[[], object], b: Callable[[], object], repeat: int) -> tuple[float, float]:
    """Fastest of ``repeat`` calls of ``a`` and of ``b``, alternated ABBA, microseconds."""
    times: tuple[list[int], list[int]] = ([], [])
    for k in range(repeat):
        for which in (0, 1) if k % 2 == 0 else (1, 0):
            f = a if which == 0 else b
            t0 = time.perf_counter_ns()
            f()
            times[which].append(time.perf_counter_ns() - t0)
    return min(times[0]) / 1e3, min(times[1]) / 1e3


def report(name: str, a: np.ndarray, b: np.ndarray) -> str:
    """One line: both medians and the per-frame ratio's median and range."""
    r = b / a
    return (
        f"{name}: 3e00d28 {np.median(a):.1f} us, this tree {np.median(b):.1f} us, per-frame "
        f"ratio median {np.median(r):.3f} (range {r.min():.3f}-{r.max():.3f}), {a.size} frames"
    )


def main() -> None:
    """Parse the arguments, check both steps agree on every frame, time them."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("before", type=Path, help="a checkout of 3e00d28 (e.g. /work/base)")
    p.add_argument("--data", type=Path, required=True, help="SemanticKITTI root or sequence")
    p.add_argument("--repeat", type=int, default=20, help="calls per frame and revision")
    args = p.parse_args()
    mod = load_before(args.before)
    old, new = mod.ColumnGround(), column.ColumnGround()
    config = load_config()
    ds = open_dataset(args.data)
    preps = [prepare(ds.load(r), "ground", config.projection) for r in ds.refs()]
    vec = mod._param_vector(*(type(getattr(old, k))(getattr(old, k)) for k in KEYS))
    step_a, step_b, kern_a, kern_b = [], [], [], []
    for prep in preps:
        want = before_step(old, prep)
        g = after_step(new, prep)
        same = [
            np.array_equal(x, y)
            for x, y in zip(want, (g.mask, g.held, g.decided, g.attached), strict=True)
        ]
        if not all(same):
            raise SystemExit(f"{prep.ref}: the steps differ (mask, held, decided, attached {same})")
        ta, tb = alternate(
            functools.partial(before_step, old, prep),
            functools.partial(after_step, new, prep),
            args.repeat,
        )
        step_a.append(ta)
        step_b.append(tb)
        geo = column.pixel_geometry(prep.image, new.point_heights)
        jumps, params = new.run_jumps(prep.image), column._param_vector(new)
        ta, tb = alternate(
            functools.partial(mod._column_ground, *geo, vec),
            functools.partial(column._column_ground, *geo, params, jumps),
            args.repeat,
        )
        kern_a.append(ta)
        kern_b.append(tb)
    print(report("column ground step", np.array(step_a), np.array(step_b)))
    print(report("_column_ground kernel", np.array(kern_a), np.array(kern_b)))


if __name__ == "__main__":
    main()
