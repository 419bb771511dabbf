"""Old against new: the clustering stage of the image methods, timed in one process, and counted.

Loads the clusterers (``flic_cli/methods/{_unionfind,base,flic,bogoslavskyi,bridge}.py``) and
``flic_cli/range_image.py`` of a base git revision beside the working tree's, computes every
frame's ground mask once (not timed), then runs ``method.segment(image, points, ground)`` -- the
stage "cluster+labels" of ``scripts/profile_stages.py``: masks, kernel and per-point labels -- with
both implementations on every frame, alternating which goes first, checks that both give the same
labels and prints the medians and 99th percentiles (one thread; glibc's malloc keeps freed
memory, as in flic's CLI, unless ``--return-freed-memory``). The ``--callgrind`` mode counts
the instructions and (simulated) branch mispredictions of each method and implementation instead
(``valgrind --tool=callgrind --branch-sim=yes``, instrumentation switched on only around one
method's pass over the frames, see ``scripts/compare_stages.py``). Valgrind's CPU has no AVX-512,
so numba compiles the kernels for AVX2 there: vectorised loops count about twice the
instructions they run natively.

Usage::

    python scripts/compare_kernels.py DATA [--methods flic0,flic14,bogoslavskyi,bridge]
        [--base REV] [--repeat 3] [--frames N] [--ground-remover paper|own] [--setting ground]
    python scripts/compare_kernels.py DATA --callgrind [--frames 10]

DATA is a Moosmann log or a SemanticKITTI folder (e.g. a log written by ``flic sample``).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

from flic_cli.runs.environment import keep_freed_memory, pin_thread_env, thread_limits

pin_thread_env(1)  # before numpy/numba are imported

import numpy as np  # noqa: E402

from flic_cli.config import load_config  # noqa: E402
from flic_cli.io import open_dataset  # noqa: E402
from flic_cli.runs.pipeline import build_segmenter, prepare  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: The base revision: the last commit before the clustering kernels of issue 11 were reworked.
BASE = "56a0905"
MODULES = (
    "flic_cli/range_image.py",
    "flic_cli/methods/_unionfind.py",
    "flic_cli/methods/base.py",
    "flic_cli/methods/flic.py",
    "flic_cli/methods/bogoslavskyi.py",
    "flic_cli/methods/bridge.py",
)
CLASSES = {"flic": "flic", "bogoslavskyi": "bogoslavskyi", "bridge": "bridge"}


def module_name(path: str) -> str:
    """``flic_cli/methods/flic.py`` -> ``base_flic_cli_methods_flic``."""
    return "base_" + path.removesuffix(".py").replace("/", "_")


def load_base(rev: str) -> dict[str, ModuleType]:
    """The base revision's modules, imported from files whose imports of each other are redirected
    to the base copies (so that numba can cache their kernels)."""
    import importlib.util

    folder = Path(tempfile.gettempdir()) / f"flic-kernels-{rev}"
    folder.mkdir(exist_ok=True)
    out = {}
    for path in MODULES:
        src = subprocess.run(
            ["git", "show", f"{rev}:{path}"], cwd=ROOT, check=True, capture_output=True, text=True
        ).stdout
        for other in MODULES:
            dotted = other.removesuffix(".py").replace("/", ".")
            src = re.sub(rf"\b{re.escape(dotted)}\b", module_name(other), src)
        name = module_name(path)
        file = folder / f"{name}.py"
        if not file.exists() or file.read_text() != src:
            file.write_text(src)
        spec = importlib.util.spec_from_file_location(name, file)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        out[path] = module
    return out


def base_method(base: dict[str, ModuleType], method: Any) -> Any:
    """The base revision's class of ``method``, with the same parameters."""
    kind = type(method).__module__.rsplit(".", 1)[-1]
    module = base[f"flic_cli/methods/{kind}.py"]
    return getattr(module, type(method).__name__)(**dataclasses.asdict(method))


def base_image(base: dict[str, ModuleType], image: Any) -> Any:
    """The same range image as the base revision's RangeImage (its own ``point_labels``)."""
    cls = base["flic_cli/range_image.py"].RangeImage
    names = {f.name for f in dataclasses.fields(cls)}
    kw = {n: getattr(image, n) for n in names if n != "counts" and hasattr(image, n)}
    return cls(**kw, **({"counts": image.point_counts()} if "counts" in names else {}))


def ground_arg(key: str, ground: Any) -> Any:
    """The ground step as an implementation takes it: the working tree's Ground, the base
    revision's mask of the cells left out."""
    return ground if key == "new" or ground is None else ground.left_out


class Frames:
    """Every frame's image, points and ground step as the clusterers take them (the ground
    step computed once, with the working tree:
    :meth:`flic_cli.runs.pipeline.Segmenter.ground_step`)."""

    def __init__(self, args: argparse.Namespace, method: str) -> None:
        cfg = load_config()
        ds = open_dataset(args.data)
        seg = build_segmenter(cfg, method, args.setting, args.ground_remover)
        self.method = seg.method
        self.items = []
        for ref in ds.refs()[: args.frames]:
            prep = prepare(ds.load(ref), args.setting, cfg.projection)
            ground = seg.ground_step(prep.image, prep.points)
            if ground is None:
                self.items.append((prep.image, prep.points, None))
            else:
                self.items.append((ground.image, prep.points, ground))


def time_both(args: argparse.Namespace) -> None:
    base = load_base(args.base)
    print(
        f"{args.data}, {args.setting} setting, ground remover {args.ground_remover}, "
        f"x {args.repeat}, one thread, base {args.base} vs working tree; segment() per frame, ms:"
    )
    print(
        f"  {'method':14s} {'base median':>11s} {'new median':>10s} {'speed-up':>8s} "
        f"{'base p99':>8s} {'new p99':>8s}  labels differ on"
    )
    for name in args.methods.split(","):
        frames = Frames(args, name)
        impls = {"base": base_method(base, frames.method), "new": frames.method}
        images = {
            "base": [base_image(base, im) for im, _, _ in frames.items],
            "new": [im for im, _, _ in frames.items],
        }
        times: dict[str, list[float]] = {"base": [], "new": []}
        for key, impl in impls.items():  # warm-up (JIT cache loads)
            _, pts, ground = frames.items[0]
            impl.segment(images[key][0], pts, ground_arg(key, ground))
        differ = 0
        for rep in range(args.repeat):
            for i, (_, pts, ground) in enumerate(frames.items):
                order = ("base", "new") if (i + rep) % 2 == 0 else ("new", "base")
                out = {}
                for key in order:
                    t = time.perf_counter()
                    out[key] = impls[key].segment(images[key][i], pts, ground_arg(key, ground))
                    times[key].append(1e3 * (time.perf_counter() - t))
                if rep == 0:
                    differ += not np.array_equal(out["base"], out["new"])
        b, w = np.median(times["base"]), np.median(times["new"])
        pb, pw = np.percentile(times["base"], 99), np.percentile(times["new"], 99)
        print(
            f"  {name:14s} {b:11.3f} {w:10.3f} {b / w:7.2f}x {pb:8.3f} {pw:8.3f}  "
            f"{differ} of {len(frames.items)} frames"
        )


CG_HELPER = r"""
#include <valgrind/callgrind.h>
void cg_toggle(void) { CALLGRIND_TOGGLE_COLLECT; }
void cg_dump(const char *name) { CALLGRIND_DUMP_STATS_AT(name); }
void cg_start(void) { CALLGRIND_START_INSTRUMENTATION; }
void cg_stop(void) { CALLGRIND_STOP_INSTRUMENTATION; }
"""


def count_all(args: argparse.Namespace) -> None:
    """Under valgrind: collect each method and implementation alone and dump its counts.

    Instrumentation is off (fast) except around each pass over the frames."""
    import ctypes

    folder = Path(tempfile.mkdtemp())
    (folder / "cg.c").write_text(CG_HELPER)
    lib = folder / "libcg.so"
    subprocess.run(["gcc", "-O1", "-shared", "-fPIC", "-o", lib, folder / "cg.c"], check=True)
    cg = ctypes.CDLL(str(lib))
    base = load_base(args.base)
    for name in args.methods.split(","):
        frames = Frames(args, name)
        impls = {"base": base_method(base, frames.method), "new": frames.method}
        for key, impl in impls.items():
            images = [base_image(base, im) if key == "base" else im for im, _, _ in frames.items]
            impl.segment(images[0], frames.items[0][1], ground_arg(key, frames.items[0][2]))
            cg.cg_start()
            cg.cg_toggle()
            for image, (_, pts, ground) in zip(images, frames.items, strict=True):
                impl.segment(image, pts, ground_arg(key, ground))
            cg.cg_toggle()
            cg.cg_dump(f"{name}:{key}".encode())
            cg.cg_stop()


def callgrind(args: argparse.Namespace) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            "valgrind",
            "--tool=callgrind",
            "--branch-sim=yes",
            "--instr-atstart=no",
            "--collect-atstart=no",
            f"--callgrind-out-file={tmp}/cg.out",
            sys.executable,
            __file__,
            str(args.data),
            "--base",
            args.base,
            "--setting",
            args.setting,
            "--ground-remover",
            args.ground_remover,
            "--methods",
            args.methods,
            "--frames",
            str(args.frames),
            "--count-all",
        ]
        env = {**os.environ, "PYTHONHASHSEED": "0"}
        res = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if res.returncode:
            raise SystemExit(f"valgrind run failed: {' '.join(cmd)}\n{res.stderr[-2000:]}")
        counts, missed = {}, {}
        for dump in Path(tmp).glob("cg.out*"):
            text = dump.read_text()
            name = re.search(r"^desc: Trigger: Client Request: (\S+)$", text, re.M)
            events = re.search(r"^events: (.*)$", text, re.M)
            totals = re.search(r"^totals: (.*)$", text, re.M)
            if name and events and totals:
                values = map(int, totals.group(1).split())
                ev = dict(zip(events.group(1).split(), values, strict=True))
                counts[name.group(1)] = ev["Ir"] / args.frames
                missed[name.group(1)] = ev["Bcm"] / args.frames
    print(
        f"per frame of segment() (valgrind --tool=callgrind --branch-sim=yes, {args.frames} "
        f"frames of {args.data}, {args.setting} setting, ground remover {args.ground_remover}): "
        "instructions, and conditional branches mispredicted by valgrind's simple predictor"
    )
    print(
        f"  {'method':14s} {'base instr.':>14s} {'new instr.':>14s} {'ratio':>6s} "
        f"{'base mispr.':>11s} {'new mispr.':>11s}"
    )
    for name in args.methods.split(","):
        b, w = counts[f"{name}:base"], counts[f"{name}:new"]
        mb, mw = missed[f"{name}:base"], missed[f"{name}:new"]
        print(f"  {name:14s} {b:14,.0f} {w:14,.0f} {b / w:5.2f}x {mb:11,.0f} {mw:11,.0f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", type=Path)
    parser.add_argument("--methods", default="flic0,flic14,bogoslavskyi,bridge")
    parser.add_argument("--base", default=BASE, help="git revision of the old implementation")
    parser.add_argument("--setting", default="ground", choices=("ground", "no-ground"))
    parser.add_argument("--ground-remover", default="paper", help="a remover's name or 'own'")
    parser.add_argument("--repeat", type=int, default=3, help="passes over the frames")
    parser.add_argument("--frames", type=int, default=None, help="use the first N frames")
    parser.add_argument("--callgrind", action="store_true", help="count instructions instead")
    parser.add_argument(
        "--return-freed-memory",
        action="store_true",
        help="leave glibc's malloc as it is (the CLI tells it to keep freed memory: without, "
        "every frame's arrays are fresh pages, and the page faults cost more than the kernels)",
    )
    parser.add_argument("--count-all", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if not args.return_freed_memory:
        keep_freed_memory()  # as flic's CLI does
    with thread_limits(1):
        if args.count_all:
            count_all(args)
        elif args.callgrind:
            if args.frames is None:
                args.frames = 10
            callgrind(args)
        else:
            time_both(args)


if __name__ == "__main__":
    main()
