"""Old against new: reading, projection and scoring timed in one process, and instruction counts.

Loads the reading (``flic_cli/io/semantickitti.py``), projection (then ``flic_cli/range_image.py``,
now ``flic_cli/projection.py``) and
scoring (``flic_cli/metrics/instances.py``) code of a base git revision beside the working tree's,
runs both on every frame, alternating which goes first, checks that they give the same results and
prints the medians (one thread). On a machine shared with other jobs wall-clock times are noisy;
the ``--callgrind`` mode counts the instructions of each stage instead (valgrind, reproducible;
needs valgrind's headers and gcc): it runs this script under ``valgrind --tool=callgrind`` with
collection switched on only around each stage's pass over the frames. Valgrind emulates a CPU
without AVX-512, so numpy runs its AVX2 code there.

Usage::

    python scripts/compare_stages.py [DATA] [--base REV] [--repeat 3] [--setting ground]
    python scripts/compare_stages.py [DATA] --callgrind [--frames 10]
    python scripts/compare_stages.py --moosmann LOG [--repeat 3]    # Moosmann frame loading

The base revision defaults to a74c9eb, the last commit before the speed work of issue 11.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

from flic_cli.runs.environment import pin_thread_env, thread_limits

pin_thread_env(1)  # before numpy/numba are imported

import numpy as np  # noqa: E402

from flic_cli import projection  # noqa: E402
from flic_cli.classes import ground_mask  # noqa: E402
from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset, semantickitti  # noqa: E402
from flic_cli.metrics import instances  # noqa: E402
from flic_cli.runs.pipeline import build_segmenter  # noqa: E402

BASE = "a74c9eb"
ROOT = Path(__file__).resolve().parents[1]
MODULES = {
    "read": "flic_cli/io/semantickitti.py",
    "project": "flic_cli/range_image.py",
    "score": "flic_cli/metrics/instances.py",
}
STAGES = tuple(MODULES)
#: The default projection, as keyword arguments of project_points (old and new).
PROJECTION = dataclasses.asdict(load_config().projection)


def load_base(rev: str) -> dict[str, ModuleType]:
    """The base revision's modules, imported from files (so that numba can cache their kernels)."""
    folder = Path(tempfile.gettempdir()) / f"flic-compare-{rev}"
    return {
        stage: load_module(rev, path, f"base_{stage}", folder) for stage, path in MODULES.items()
    }


def load_module(rev: str, path: str, name: str, folder: Path) -> ModuleType:
    """Module ``path`` of git revision ``rev``, written to ``folder`` and imported as ``name``."""
    folder.mkdir(exist_ok=True)
    src = subprocess.run(
        ["git", "show", f"{rev}:{path}"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    file = folder / f"{name}.py"
    if not file.exists() or file.read_text() != src:
        file.write_text(src)
    spec = importlib.util.spec_from_file_location(name, file)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


class Frames:
    """The frames' inputs of every stage, prepared once with the working tree's code."""

    def __init__(self, data: Path, setting: str, method: str, limit: int | None) -> None:
        cfg = load_config()
        ds = open_dataset(data)
        seg = build_segmenter(cfg, method, setting)
        self.refs = ds.refs()[:limit]
        self.items: list[dict[str, Any]] = []
        for ref in self.refs:
            scan = semantickitti.read_scan(ref.path, ref.label_path)
            keep = None if setting == "ground" else ~ground_mask(scan.labels)
            image = projection.project_points(scan.points, keep=keep, **PROJECTION)
            points = scan.points if keep is None else scan.points[keep]
            gt = scan.labels if keep is None else scan.labels[keep]
            pred = seg(image, points)[0]
            item = {"ref": ref, "points": scan.points, "keep": keep, "gt": gt, "pred": pred}
            self.items.append({**item, "p": points})


def run_stage(stage: str, impl: dict[str, ModuleType], item: dict[str, Any]) -> Any:
    """One stage of one frame with one implementation; returns what it computed."""
    if stage == "read":
        return impl["read"].read_scan(item["ref"].path, item["ref"].label_path)
    if stage == "project":
        return impl["project"].project_points(item["points"], keep=item["keep"], **PROJECTION)
    mod = impl["score"]
    if hasattr(mod, "score_frame"):
        return mod.score_frame(item["gt"], item["pred"], item["p"])
    return mod.match_objects(item["gt"], item["pred"], item["p"]), mod.segmentation_stats(
        item["gt"], item["pred"]
    )


def same(stage: str, a: Any, b: Any) -> bool:
    """Whether two implementations' results of a stage are equal (bit for bit, NaN == NaN)."""
    if stage == "read":
        return all(
            (x is None and y is None) or np.array_equal(x, y) for x, y in zip(a, b, strict=True)
        )
    if stage == "project":
        return all(
            np.array_equal(getattr(a, k), getattr(b, k))
            for k in ("ranges", "elevation", "point_pixel")
        ) and (a.projection == b.projection)
    (ma, sa), (mb, sb) = a, b
    return sa == sb and all(
        np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
        for x, y in zip(ma.as_dict().values(), mb.as_dict().values(), strict=True)
    )


def time_both(args: argparse.Namespace) -> None:
    impls = {"base": load_base(args.base), "new": current()}
    frames = Frames(args.data, args.setting, args.method, args.frames)
    times: dict[tuple[str, str], list[float]] = {}
    mismatches = dict.fromkeys(STAGES, 0)
    for stage in STAGES:  # warm-up (JIT cache loads)
        for impl in impls.values():
            run_stage(stage, impl, frames.items[0])
    for rep in range(args.repeat):
        for i, item in enumerate(frames.items):
            for stage in STAGES:
                order = ["base", "new"] if (i + rep) % 2 == 0 else ["new", "base"]
                results = {}
                for name in order:
                    t = time.perf_counter()
                    results[name] = run_stage(stage, impls[name], item)
                    times.setdefault((stage, name), []).append(1e3 * (time.perf_counter() - t))
                if rep == 0 and not same(stage, results["base"], results["new"]):
                    mismatches[stage] += 1
    n = len(frames.items)
    print(
        f"{args.method}, {args.setting} setting, {n} frames x {args.repeat}, one thread, "
        f"base {args.base} vs working tree; median ms per frame:"
    )
    print(f"  {'stage':8s} {'base':>8s} {'new':>8s} {'speed-up':>9s}  results differ on")
    for stage in STAGES:
        b, w = np.median(times[(stage, "base")]), np.median(times[(stage, "new")])
        print(f"  {stage:8s} {b:8.3f} {w:8.3f} {b / w:8.2f}x  {mismatches[stage]} of {n} frames")


def time_moosmann(args: argparse.Namespace) -> None:
    """Old and new ``MoosmannDataset.load`` (PNG decode, checks, points) on every frame of a log."""
    folder = Path(tempfile.gettempdir()) / f"flic-compare-{args.base}"
    base = load_module(args.base, "flic_cli/io/moosmann.py", "base_moosmann", folder)
    datasets = {"base": base.MoosmannDataset(args.moosmann), "new": open_dataset(args.moosmann)}
    refs = datasets["new"].refs()[: args.frames]
    times: dict[str, list[float]] = {"base": [], "new": []}
    differ = 0
    for name in times:
        datasets[name].load(refs[0])
    for rep in range(args.repeat):
        for i, ref in enumerate(refs):
            out = {}
            for name in ("base", "new") if (i + rep) % 2 == 0 else ("new", "base"):
                t = time.perf_counter()
                out[name] = datasets[name].load(ref)
                times[name].append(1e3 * (time.perf_counter() - t))
            a, b = out["base"], out["new"]
            differ += rep == 0 and not (
                np.array_equal(a.points, b.points)
                and np.array_equal(a.image.ranges, b.image.ranges)
                and np.array_equal(a.image.point_pixel, b.image.point_pixel)
            )
    b, w = np.median(times["base"]), np.median(times["new"])
    print(
        f"Moosmann load, {len(refs)} frames x {args.repeat} of {args.moosmann}, one thread, "
        f"base {args.base} vs working tree: median {b:.3f} -> {w:.3f} ms ({b / w:.2f}x), "
        f"results differ on {differ} frames"
    )


def current() -> dict[str, ModuleType]:
    return {"read": semantickitti, "project": projection, "score": instances}


CG_HELPER = r"""
#include <valgrind/callgrind.h>
void cg_toggle(void) { CALLGRIND_TOGGLE_COLLECT; }
void cg_dump(const char *name) { CALLGRIND_DUMP_STATS_AT(name); }
"""


def count_all(args: argparse.Namespace) -> None:
    """Run under valgrind: collect each stage and implementation alone and dump its counts.

    Collection starts off (``--collect-atstart=no``); a tiny C helper (compiled here, it only
    wraps valgrind's client requests) switches it on around one stage's pass over the frames and
    dumps the counts under the name ``stage:impl``.
    """
    import ctypes

    folder = Path(tempfile.mkdtemp())
    (folder / "cg.c").write_text(CG_HELPER)
    lib = folder / "libcg.so"
    subprocess.run(["gcc", "-O1", "-shared", "-fPIC", "-o", lib, folder / "cg.c"], check=True)
    cg = ctypes.CDLL(str(lib))
    impls = {"base": load_base(args.base), "new": current()}
    frames = Frames(args.data, args.setting, args.method, args.frames)
    for stage in args.stages.split(","):
        for name, impl in impls.items():
            run_stage(stage, impl, frames.items[0])  # warm-up: JIT compile or cache load
            cg.cg_toggle()
            for item in frames.items:
                run_stage(stage, impl, item)
            cg.cg_toggle()
            cg.cg_dump(f"{stage}:{name}".encode())


def callgrind(args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory() as tmp_dir:
        tmp = args.keep_dumps or tmp_dir
        Path(tmp).mkdir(parents=True, exist_ok=True)
        cmd = [
            "valgrind",
            "--tool=callgrind",
            "--collect-atstart=no",
            f"--callgrind-out-file={tmp}/cg.out",
            sys.executable,
            __file__,
            str(args.data),
            "--base",
            args.base,
            "--setting",
            args.setting,
            "--method",
            args.method,
            "--frames",
            str(args.frames),
            "--stages",
            args.stages,
            "--count-all",
        ]
        env = {**os.environ, "PYTHONHASHSEED": "0"}
        res = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if res.returncode:
            raise SystemExit(f"valgrind run failed: {' '.join(cmd)}\n{res.stderr[-2000:]}")
        counts, libm = {}, {}
        for dump in Path(tmp).glob("cg.out*"):
            text = dump.read_text()
            name = re.search(r"^desc: Trigger: Client Request: (\S+)$", text, re.M)
            total = re.search(r"^(?:summary|totals): (\d+)", text, re.M)
            if name and total:
                counts[name.group(1)] = int(total.group(1)) / args.frames
                libm[name.group(1)] = libm_share(dump) / args.frames
    print(
        f"instructions per frame (valgrind --tool=callgrind, {args.frames} frames, "
        f"{args.method}, {args.setting} setting); in brackets those in libm (numpy's atan2 and "
        "asin, scalar under valgrind, AVX-512 SVML natively):"
    )
    print(f"  {'stage':8s} {'base':>26s} {'new':>26s} {'ratio':>7s}")
    for stage in args.stages.split(","):
        b, w = counts[f"{stage}:base"], counts[f"{stage}:new"]
        lb, lw = libm[f"{stage}:base"], libm[f"{stage}:new"]
        print(f"  {stage:8s} {b:14,.0f} ({lb:9,.0f}) {w:14,.0f} ({lw:9,.0f}) {b / w:6.2f}x")


def libm_share(dump: Path) -> int:
    """Instructions of one callgrind dump spent in libm's math functions (callgrind_annotate)."""
    out = subprocess.run(
        ["callgrind_annotate", "--inclusive=no", "--threshold=100", str(dump)],
        capture_output=True,
        text=True,
    ).stdout
    total = 0
    for line in out.splitlines():
        m = re.match(r"\s*([\d,]+) \(", line)
        if m and ("libm.so" in line or "ieee754" in line):
            total += int(m.group(1).replace(",", ""))
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default=ROOT.parent / "shared/data/semantickitti")
    parser.add_argument("--base", default=BASE, help="git revision of the old implementation")
    parser.add_argument("--method", default="flic0", help="method whose labels are scored")
    parser.add_argument("--setting", default="ground", choices=("ground", "no-ground"))
    parser.add_argument("--repeat", type=int, default=3, help="passes over the frames")
    parser.add_argument("--frames", type=int, default=None, help="use the first N frames")
    parser.add_argument("--callgrind", action="store_true", help="count instructions instead")
    parser.add_argument(
        "--moosmann", type=Path, default=None, help="time the loading of this Moosmann log instead"
    )
    parser.add_argument("--stages", default=",".join(STAGES), help="stages to count")
    parser.add_argument(
        "--keep-dumps", help="folder for callgrind's dumps (see callgrind_annotate)", default=None
    )
    parser.add_argument(
        "--keep-freed-memory",
        action="store_true",
        help="glibc keeps freed memory for reuse (see profile_stages.py)",
    )
    parser.add_argument("--count-all", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    args.data = Path(args.data)
    if args.keep_freed_memory:
        from profile_stages import keep_freed_memory  # scripts/ is on sys.path

        keep_freed_memory()
    with thread_limits(1):
        if args.count_all:
            count_all(args)
        elif args.moosmann:
            time_moosmann(args)
        elif args.callgrind:
            if args.frames is None:
                args.frames = 10
            callgrind(args)
        else:
            time_both(args)


if __name__ == "__main__":
    main()
