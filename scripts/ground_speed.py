"""Time the ground removers alone, interleaved frame by frame, on one data set; or count their
instructions per frame under callgrind.

Every frame is read and projected once; then each round calls every remover once per frame, in
turn (the order turns from frame to frame, since the first call on a frame finds it out of
cache), so that all removers see the same machine load. Prints (and optionally writes) the median,
p5 and p95 milliseconds per frame and each remover's median relative to the first one. Removers
that need points get the frame's points. Timings on a shared machine are noisy: compare the
relative figures of one run, not absolute figures across runs.

A remover is a registered name, optionally with parameters (``column:neighbour_px=0``), or
``column-previous``: the implementation of the ``column`` remover before step 6 and the kernel
rework (commit 4eec351), kept in ``tests/test_ground_column.py`` as the reference of the tests,
or ``NAME@REV``: the remover ``NAME`` with its defaults as it was at git revision ``REV`` (its
module ``flic_cli/ground/NAME.py`` of that revision, loaded beside the working tree's); the
table then says on how many frames its masks differ from those of the working tree's ``NAME``.

``--per-point`` times what the ground table times instead of the mask call:
:func:`flic_cli.ground.base.extract_ground`, the remover with its per-point decision (step 7 of
``column``) and the image the clusterers see; ``NAME@REV`` is then the remover's class at that
revision, with its defaults, and the table says on how many frames its per-point decision or its
point map differs.

``--instructions`` counts instead of timing (deterministic, whatever the machine's load): for
every remover it runs this script under ``valgrind --tool=callgrind`` with instrumentation off,
switches it on (``callgrind_control -i on``) once the remover is compiled and warm, and divides
the instructions of the timed loop (remover calls and their Python wrappers) by the calls.

Usage::

    python scripts/ground_speed.py /tmp/s/moosmann --removers paper,column,bogoslavskyi \\
        --rounds 5 --out results/ground/speed_removers_moosmann.csv
    python scripts/ground_speed.py /tmp/s/moosmann \\
        --removers column-previous,column,column:neighbour_px=0 --rounds 20
    python scripts/ground_speed.py /tmp/s/moosmann \\
        --removers column-previous,column,column:neighbour_px=0 --instructions --rounds 2
    python scripts/ground_speed.py /tmp/kitti-log --removers column@a57d9e3~1,column --rounds 5
    python scripts/ground_speed.py ../shared/data/semantickitti --removers column@HEAD~1,column \\
        --per-point --rounds 5
"""

from __future__ import annotations

import argparse
import ast
import functools
import importlib.util
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from flic_cli.config import load_config
from flic_cli.ground.base import extract_ground
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.runs.pipeline import prepare

ROOT = Path(__file__).resolve().parents[1]


def previous_column():
    """The ``column`` remover as it was before step 6 (kept in the tests as their reference)."""
    # under the module name pytest gives it, so that numba's cache of its kernels is valid
    spec = importlib.util.spec_from_file_location(
        "test_ground_column", ROOT / "tests" / "test_ground_column.py"
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules["test_ground_column"] = mod
    spec.loader.exec_module(mod)
    return lambda image, points=None: mod._reference(image)


def remover_at(cfg, name: str, rev: str, per_point: bool = False):
    """The remover ``name`` with its defaults at git revision ``rev``: its module's
    ``NAME_ground`` (the mask), or with ``per_point`` its class (as ``extract_ground`` runs it)."""
    src = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{rev}:flic_cli/ground/{name}.py"],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    folder = Path(tempfile.mkdtemp(prefix="flic-remover-"))
    module = f"{name}_at_{re.sub(r'[^0-9A-Za-z]', '_', rev)}"
    path = folder / f"{module}.py"
    path.write_text(src)
    spec = importlib.util.spec_from_file_location(module, path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[module] = mod
    spec.loader.exec_module(mod)
    if per_point:
        return getattr(mod, type(cfg.remover(name)).__name__)()
    return lambda image, points=None: getattr(mod, f"{name}_ground")(image)


def make_remover(cfg, spec: str, per_point: bool = False):
    """A remover from ``NAME``, ``NAME:param=value,...`` or ``NAME@REV`` (see the module
    docstring)."""
    if spec == "column-previous":
        return previous_column()
    if "@" in spec:
        return remover_at(cfg, *spec.split("@", 1), per_point=per_point)
    name, _, params = spec.partition(":")
    remover = cfg.remover(name)
    if params:
        kw = {k: ast.literal_eval(v) for k, v in (p.split("=") for p in params.split(";"))}
        remover = type(remover)(**{**remover.__dict__, **kw})
    if per_point:
        return remover
    return lambda image, points=None: remover.extract(image, points).mask


def _same(a, b) -> bool:
    """Whether two masks, or two ground steps' decisions and point maps, are equal."""
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b)
    return (
        np.array_equal(a.mask, b.mask)
        and np.array_equal(a.on_ground, b.on_ground)
        and np.array_equal(a.image.point_pixel, b.image.point_pixel)
        and np.array_equal(a.image.point_counts(), b.image.point_counts())
    )


def load_frames(data: Path, cfg, limit: int | None) -> list:
    ds = open_dataset(data)
    return [prepare(ds.load(ref), "ground", cfg.projection) for ref in ds.refs()[:limit]]


def child(args) -> None:
    """Under callgrind: warm up, report READY, wait for the go file, run the loop, exit."""
    cfg = load_config()
    frames = load_frames(args.data, cfg, args.frames)
    remover = make_remover(cfg, args.child)
    for prep in frames[:2]:
        remover(prep.image, prep.points)
    import gc

    gc.collect()
    gc.disable()
    print(f"READY {os.getpid()} {len(frames)}", flush=True)
    go = Path(args.go)
    while not go.exists():
        time.sleep(0.05)
    for _ in range(args.rounds):
        for prep in frames:
            remover(prep.image, prep.points)
    sys.stdout.flush()
    os._exit(0)  # no interpreter shutdown under instrumentation


def count_instructions(args, spec: str) -> dict:
    """Instructions and conditional branches per call of one remover (callgrind)."""
    with tempfile.TemporaryDirectory() as tmp:
        go = Path(tmp) / "go"
        log = Path(tmp) / "log"
        cmd = ["valgrind", "--tool=callgrind", "--instr-atstart=no", "--branch-sim=yes",
               f"--callgrind-out-file={tmp}/out", sys.executable, __file__, str(args.data),
               "--child", spec, "--go", str(go), "--rounds", str(args.rounds)]  # fmt: skip
        if args.frames:
            cmd += ["--frames", str(args.frames)]
        with open(log, "w") as fh:
            proc = subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT)
            while not re.search(r"READY \d+ \d+", log.read_text()):
                if proc.poll() is not None:
                    raise RuntimeError(log.read_text()[-2000:])
                time.sleep(0.5)
            pid, n_frames = map(int, re.search(r"READY (\d+) (\d+)", log.read_text()).groups())
            subprocess.run(["callgrind_control", "-i", "on", str(pid)], capture_output=True)
            go.touch()
            proc.wait()
        text = log.read_text()
    ir, bc, bcm = map(int, re.search(r"Collected : (\d+) (\d+) (\d+)", text).groups())
    calls = args.rounds * n_frames
    return {"remover": spec, "calls": calls, "instructions_per_call": round(ir / calls),
            "cond_branches_per_call": round(bc / calls),
            "mispredicted_per_call_simulated": round(bcm / calls)}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--removers", default="paper,column,bogoslavskyi")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=None, help="first N frames only")
    parser.add_argument("--instructions", action="store_true", help="count under callgrind")
    parser.add_argument(
        "--per-point", action="store_true", help="time extract_ground (with per-point decisions)"
    )
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    parser.add_argument("--go", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return

    names = args.removers.split(",")
    if args.instructions:
        df = pd.DataFrame([count_instructions(args, n) for n in names])
    else:
        cfg = load_config()
        frames = load_frames(args.data, cfg, args.frames)
        removers = {n: make_remover(cfg, n, args.per_point) for n in names}
        if args.per_point:
            calls = {n: functools.partial(extract_ground, r) for n, r in removers.items()}
        else:
            calls = removers
        for call in calls.values():  # warm-up: JIT compilation or cache load
            call(frames[0].image, frames[0].points)
        differ = {}
        for n in names:  # an old revision's masks (or decisions) against the working tree's
            if "@" in n:
                current = make_remover(cfg, n.split("@")[0], args.per_point)
                if args.per_point:
                    current = functools.partial(extract_ground, current)
                differ[n] = sum(
                    not _same(calls[n](p.image, p.points), current(p.image, p.points))
                    for p in frames
                )
        times: dict[str, list[float]] = {n: [] for n in names}
        import gc

        gc.collect()
        gc.disable()
        order = list(calls.items())
        for k in range(args.rounds):
            for i, prep in enumerate(frames):
                # the order turns from frame to frame: the first remover after a new frame
                # finds it out of cache, the others in it
                turn = (i + k) % len(order)
                for n, remover in order[turn:] + order[:turn]:
                    t0 = time.perf_counter()
                    remover(prep.image, prep.points)
                    times[n].append(time.perf_counter() - t0)
        h, w = frames[0].image.ranges.shape
        base = float(np.median(times[names[0]]))
        rows = [
            {
                "remover": n,
                "image": f"{w}x{h}",
                "calls": len(t),
                "median_ms": round(1000 * float(np.median(t)), 4),
                "p5_ms": round(1000 * float(np.percentile(t, 5)), 4),
                "p95_ms": round(1000 * float(np.percentile(t, 95)), 4),
                f"median_vs_{names[0]}": round(float(np.median(t)) / base, 2),
                "frames_whose_mask_differs": differ.get(n, ""),
            }
            for n, t in times.items()
        ]
        df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)


if __name__ == "__main__":
    main()
