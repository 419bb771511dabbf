"""Studies of the ground removers on a labelled data set (results/ground/README.md cites each).

From the repository root, with the dev install; ``DATA`` is a SemanticKITTI root (or any
labelled data set flic reads), e.g. ``../shared/data/semantickitti``::

    python scripts/ground_study.py table DATA --evaluate paper=DIR --out results/ground/table.csv
    python scripts/ground_study.py speed DATA --removers column,paper --out CSV
    python scripts/ground_study.py sweep DATA --params noise_m,kerb_m --out CSV
    python scripts/ground_study.py oracle DATA --methods flic0,bridge --out CSV --counts
    python scripts/ground_study.py losses DATA --method bridge --remover column --out PREFIX
    python scripts/ground_study.py heights DATA --out results/ground/pixel_heights.csv
    python scripts/ground_study.py figure DATA --sequence 08 --frame 0 --out PNG

``python scripts/ground_study.py STUDY --help`` says what each one measures and writes; the
exact commands of the committed files are step ``ground`` (and ``ground-sweep``,
``ground-speed``, ``bridge-cases``) of ``scripts/make_results.sh``.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import gc
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _studies import Studies, run_studies  # scripts/_studies.py
from numba import njit
from tqdm import tqdm

from flic_cli.classes import GROUND_LUT, THING_LUT, ground_mask, thing_mask
from flic_cli.config import load_config
from flic_cli.ground import ColumnGround
from flic_cli.ground.base import Ground, extract_ground, leave_pixels, pixel_owners
from flic_cli.ground.column import pixel_geometry
from flic_cli.io import open_dataset
from flic_cli.io.atomic import write_table
from flic_cli.labels import instance, semantic
from flic_cli.metrics import match_objects
from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores, point_ground
from flic_cli.runs.pipeline import build_segmenter, cluster_ground, prepare

SHARED = Path("../shared/data/semantickitti")


def load_frames(root: Path, cfg, limit: int | None = None, no_ground: bool = False) -> list:
    """Every frame (the first ``limit``) prepared in the ground setting (every point projected);
    with ``no_ground``, (ground-setting frame, no-ground frame) pairs."""
    ds = open_dataset(root)
    out = []
    for ref in ds.refs()[:limit]:
        frame = ds.load(ref)
        g = prepare(frame, "ground", cfg.projection)
        out.append((g, prepare(frame, "no-ground", cfg.projection)) if no_ground else g)
    return out


def iou_mu(pairs: list[tuple], methods: dict, grounds: list[Ground] | None) -> dict[str, float]:
    """IoU_mu in % per method over (ground, no-ground) frame pairs; ``grounds`` None = the
    no-ground setting (the ground classes removed by label), else one mask per frame."""
    ious: dict[str, list] = {m: [] for m in methods}
    for k, (g, n) in enumerate(pairs):
        for name, method in methods.items():
            if grounds is None:
                labels = method.segment(n.image, n.points, None)
                ious[name].append(match_objects(n.labels, labels).iou)
            else:
                labels = cluster_ground(method, g.points, grounds[k])
                ious[name].append(match_objects(g.labels, labels).iou)
    return {m: 100 * float(np.mean(np.concatenate(v))) for m, v in ious.items()}


def pooled_scores(pairs: list[tuple], grounds: list[Ground]) -> dict[str, float]:
    """Ground precision / recall / F1 / thing points removed (%), pooled over the frames."""
    counts = sum(
        (ground_counts(g.labels, ground.on_ground) for (g, _), ground in
         zip(pairs, grounds, strict=True)), GroundCounts()
    )  # fmt: skip
    return {k: round(v, 2) for k, v in ground_scores(counts).items()}


# ---- table -------------------------------------------------------------------------------------


def table(args: argparse.Namespace) -> None:
    """The ground table: every ground remover on a labelled data set, with the clusterers' IoU_mu.

    Per remover, over all frames of the ground setting (every point of the scan projected):
    precision, recall and F1 of its ground decision against the ground classes, the share of
    thing-object points it removes (:mod:`flic_cli.metrics.ground`), and its median time per
    frame (the remover alone with its per-point decisions,
    :func:`flic_cli.ground.base.extract_ground`; single-threaded kernels, after a warm-up,
    ``--repeat`` calls per frame, the median kept). With ``--evaluate REMOVER=DIR``, the IoU_mu
    of every method in the ground and no-ground settings are read from ``DIR/table.csv`` of a
    ``flic evaluate --setting both --ground-remover REMOVER`` run and added as
    ``iou_ground_METHOD`` / ``gap_METHOD`` (no-ground minus ground) columns.
    """
    cfg = load_config()
    frames = load_frames(args.data, cfg)
    evaluated = dict(item.split("=", 1) for item in args.evaluate)
    rows = []
    for name in args.removers.split(","):
        remover = cfg.remover(name)
        extract_ground(remover, frames[0].image, frames[0].points)  # warm-up (JIT, caches)
        counts = GroundCounts()
        times = []
        for prep in frames:
            per_call = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                ground = extract_ground(remover, prep.image, prep.points)
                per_call.append(time.perf_counter() - t0)
            times.append(float(np.median(per_call)))
            counts = counts + ground_counts(prep.labels, ground.on_ground)
        row = {"remover": name}
        row.update({k: round(v, 2) for k, v in ground_scores(counts).items()})
        row["ms_per_frame"] = round(1000 * float(np.median(times)), 3)
        if name in evaluated:
            evaluation = pd.read_csv(Path(evaluated[name]) / "table.csv")
            for _, t in evaluation.iterrows():
                row[f"iou_ground_{t['method']}"] = t["iou_mu_ground"]
                row[f"gap_{t['method']}"] = round(t["iou_mu_no_ground"] - t["iou_mu_ground"], 2)
        rows.append(row)
        print(row, flush=True)
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(df.T.to_string(header=False))


def _table_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--removers", default="paper,bogoslavskyi,column,patchworkpp")
    p.add_argument("--evaluate", action="append", default=[], metavar="REMOVER=DIR")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--out", type=Path, default=Path("results/ground/table.csv"))


# ---- speed -------------------------------------------------------------------------------------


def make_remover(cfg, spec: str):
    """A remover from ``NAME`` or ``NAME:param=value;...`` (the registered remover with those
    parameters changed)."""
    name, _, params = spec.partition(":")
    remover = cfg.remover(name)
    if params:
        kw = {k: ast.literal_eval(v) for k, v in (p.split("=") for p in params.split(";"))}
        remover = type(remover)(**{**remover.__dict__, **kw})
    return remover


def speed(args: argparse.Namespace) -> None:
    """Time the ground removers alone, interleaved frame by frame, on one data set.

    Every frame is read and projected once; then each round calls every remover once per frame,
    in turn (the order turns from frame to frame, since the first call on a frame finds it out
    of cache), so that all removers see the same machine load. Prints (and optionally writes)
    the median, p5 and p95 milliseconds per frame and each remover's median relative to the
    first one. Removers that need points get the frame's points. Timings on a shared machine
    are noisy: compare the relative figures of one run, not absolute figures across runs.

    Each call is what ``table`` and the runs time: ``remover.extract(image, points)``, the
    remover's whole decision (its mask, its per-point decision such as step 7 of ``column``, and
    the image the clusterers see). A remover is a registered name, optionally with parameters
    separated by ``;`` (``column:hidden_points=False``, ``column:neighbour_px=0;under_m=1.0``).
    """
    names = args.removers.split(",")
    cfg = load_config()
    frames = load_frames(args.data, cfg, args.frames)
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


def _speed_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--removers", default="paper,column,bogoslavskyi")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--frames", type=int, default=None, help="first N frames only")
    p.add_argument("--out", type=Path, default=None)


# ---- sweep -------------------------------------------------------------------------------------

#: Values tried per parameter of ``column`` (the default is always included).
GRID: dict[str, list[float]] = {
    "noise_m": [0.02, 0.03, 0.05, 0.08],
    "slope_change_deg": [0.5, 1.0, 2.0, 3.0],
    "kerb_m": [0.1, 0.15, 0.2, 0.25],
    "max_step_m": [0.3, 0.4, 0.6],
    "flat_deg": [10.0, 15.0, 20.0],
    "seed_tolerance_m": [0.1, 0.2, 0.3],
    "base_band_m": [0.0, 0.05, 0.1, 0.15],
    # step 6, row neighbours (0 columns turns it off)
    "neighbour_px": [0, 3, 5, 10, 20, 40],
    "neighbour_band_m": [0.02, 0.03, 0.05, 0.08, 0.12],
    "foot_deg": [15.0, 20.0, 30.0, 45.0, 60.0],
    "under_m": [0.0, 0.5, 1.0, 2.0, 3.0, 5.0],
    "face_deg": [15.0, 20.0, 30.0, 45.0, 60.0, 90.0],
    # the pixels' geometry on projected scans, and step 7 (hidden points)
    "point_heights": [False, True],
    "hidden_points": [False, True],
    # step 8, the feet held out and attached
    "hold_feet": [False, True],
    "attach_m": [0.5, 1.0, 1.5, 2.5],
}


def sweep(args: argparse.Namespace) -> None:
    """Sweep the parameters of the ``column`` ground remover, one at a time around the defaults.

    For every parameter value: the ground scores over all frames (precision, recall, F1 against
    the ground classes, share of thing-object points removed; :mod:`flic_cli.metrics.ground`)
    and the ground-setting IoU_mu of the clusterers with that mask, next to their no-ground
    IoU_mu (the ground classes removed by label). Runs on ``DATA`` and on the synthetic sample
    (written to a temporary folder), so that no parameter is chosen on one data set alone.
    Writes one CSV row per (data set, parameter, value) and prints the table.
    """
    from flic_cli.sample import write_sample

    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    defaults = {f.name: f.default for f in dataclasses.fields(ColumnGround)}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        sample = write_sample(Path(tmp), frames=args.sample_frames)
        sets = {"semantickitti": args.data, "synthetic": sample.kitti_root}
        for set_name, root in sets.items():
            pairs = load_frames(root, cfg, no_ground=True)
            reference = iou_mu(pairs, methods, None)
            swept = args.params.split(",")
            runs = [("default", None)] + [(p, v) for p in swept for v in GRID[p]
                                          if v != defaults[p]]  # fmt: skip
            for param, value in runs:
                remover = ColumnGround(**({} if param == "default" else {param: value}))
                grounds = [extract_ground(remover, g.image, g.points) for g, _ in pairs]
                row = {"data": set_name, "param": param,
                       "value": "" if value is None else value}  # fmt: skip
                row.update(pooled_scores(pairs, grounds))
                got = iou_mu(pairs, methods, grounds)
                row.update({f"iou_{m}": round(got[m], 2) for m in methods})
                for m in methods:
                    row[f"gap_{m}"] = round(round(reference[m], 2) - row[f"iou_{m}"], 2)
                rows.append(row)
                print(row, flush=True)
    df = pd.DataFrame(rows)
    write_table(args.out, df)
    print(df.to_string(index=False))


def _sweep_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, default=Path("results/ground/sweep_column.csv"))
    p.add_argument("--methods", default="flic0,flic6,flic14")
    p.add_argument("--sample-frames", type=int, default=20, help="synthetic frames")
    p.add_argument("--params", default=",".join(GRID), help="parameters to sweep")


# ---- oracle ------------------------------------------------------------------------------------

CATEGORIES = ("free", "under", "foot", "free-thing", "under-thing", "foot-thing")


@njit(cache=True)
def categories(rho: np.ndarray, z: np.ndarray, thing: np.ndarray) -> np.ndarray:
    """(H, W) int8 index into :data:`CATEGORIES` (-1 where empty)."""
    h, w = rho.shape
    out = np.full((h, w), -1, dtype=np.int8)
    tan30 = np.tan(np.radians(30.0))
    for r in range(h):
        for c in range(w):
            if rho[r, c] <= 0.0:
                continue
            k = 0
            for ra in range(r - 1, max(r - 4, -1), -1):
                if rho[ra, c] <= 0.0:
                    continue
                d = rho[ra, c] - rho[r, c]
                if d < -0.3:
                    k = 1
                elif z[ra, c] - z[r, c] > tan30 * abs(d):
                    k = 2
                if thing[ra, c]:
                    k += 3
                break
            out[r, c] = k
    return out


@njit(cache=True)
def row_height(rho: np.ndarray, z: np.ndarray, taken: np.ndarray) -> np.ndarray:
    """Height of every pixel above the mean of the taken pixels of its row within 10 columns
    and 1 m of range (NaN where there are none)."""
    h, w = rho.shape
    out = np.full((h, w), np.nan)
    for r in range(h):
        for c in range(w):
            if rho[r, c] <= 0.0:
                continue
            s = 0.0
            n = 0
            for q in range(max(c - 10, 0), min(c + 11, w)):
                if taken[r, q] and abs(rho[r, q] - rho[r, c]) < 1.0:
                    s += z[r, q]
                    n += 1
            if n:
                out[r, c] = z[r, c] - s / n
    return out


def oracle(args: argparse.Namespace) -> None:
    """How close a per-pixel ground remover can get: the clusterers' IoU_mu gaps with masks
    taken from the labels, and with the labels' decision withheld where geometry cannot know it.

    Every pixel (at its nearest point's height, as ``column`` sees it) gets a category from the
    next valid cell above it (within 3 rows): ``under`` (that cell is nearer by more than 0.3 m:
    an occluder), ``foot`` (it rises from the pixel more steeply than 30 deg), else ``free``
    (farther, flat, or nothing above); ``-thing`` when the point owning that cell is a thing
    object's (a label, which a remover does not have). Masks:

    - ``labels, per point``: every point of a ground class is ground, whatever its pixel (the
      points taken outside ground pixels leave their pixel, as step 7's do: a perfect per-point
      remover);
    - ``labels``: a pixel is ground when the point that owns it (the nearest) is of a ground
      class;
    - ``labels - thing feet``: the same, but ground pixels under or at the foot of a thing
      object left (what a remover that keeps every object's foot does);
    - ``labels - other feet``: ground pixels at the foot of anything else left;
    - ``column``: flic's remover as ``flic evaluate`` runs it (steps 1-8: hidden points decided
      one by one, the feet held out and attached); ``column + labels at thing feet``: the
      remover's pixel mask (steps 1-6), with the labels' decision on the pixels under or at the
      foot of thing objects.

    Writes one row per mask: ground precision / recall / F1, thing points removed, IoU_mu per
    method and the gap to the no-ground setting. With ``--counts`` it also prints, for the
    pixels the remover leaves within ``--band`` of the ground taken in the same row (+-10
    columns, same range within 1 m), how many are labelled ground, thing or other, per category:
    the split that no geometric rule sees.
    """
    cfg = load_config()
    methods = {m: cfg.method(m).method for m in args.methods.split(",")}
    column = cfg.remover("column")
    grounds: dict[str, list[Ground]] = {k: [] for k in (
        "labels, per point", "labels", "labels - thing feet", "labels - other feet", "column",
        "column + labels at thing feet")}  # fmt: skip
    pairs = load_frames(args.data, cfg, no_ground=True)
    counts = np.zeros((len(CATEGORIES), 3), dtype=np.int64)
    for g, _ in pairs:
        img = g.image
        owner = pixel_owners(img, g.points).reshape(img.ranges.shape)
        lab = np.where(owner >= 0, g.labels[np.maximum(owner, 0)], 0)
        sem = semantic(lab)
        thing = THING_LUT[sem] & (instance(lab) > 0) & (owner >= 0)
        gr = GROUND_LUT[sem] & (owner >= 0)
        rho, z = pixel_geometry(img)[:2]
        cat = categories(rho, z, thing)
        thing_feet = (cat == 4) | (cat == 5)
        other_feet = (cat == 1) | (cat == 2)
        col = column.extract(img, g.points).mask
        on_ground = GROUND_LUT[semantic(g.labels)]
        grounds["labels, per point"].append(Ground(gr, leave_pixels(img, gr, on_ground), on_ground))
        for name, mask in (
            ("labels", gr),
            ("labels - thing feet", gr & ~thing_feet),
            ("labels - other feet", gr & ~other_feet),
            ("column + labels at thing feet", np.where(thing_feet, gr, col)),
        ):
            grounds[name].append(Ground(mask, img))
        grounds["column"].append(extract_ground(column, img, g.points))
        if args.counts:
            hh = row_height(rho, z, col)
            near = (img.ranges > 0) & ~col & (np.abs(np.nan_to_num(hh, nan=9.0)) <= args.band)
            for k in range(len(CATEGORIES)):
                s = near & (cat == k)
                counts[k] += [(s & gr).sum(), (s & thing).sum(), (s & ~gr & ~thing).sum()]
    reference = iou_mu(pairs, methods, None)
    rows = []
    for name, gs in grounds.items():
        row = {"mask": name, **pooled_scores(pairs, gs)}
        got = iou_mu(pairs, methods, gs)
        for m in methods:
            row[f"iou_{m}"] = round(got[m], 2)
            row[f"gap_{m}"] = round(reference[m] - got[m], 2)
        rows.append(row)
    df = pd.DataFrame(rows)
    print(df.to_string(index=False))
    if args.out is not None:
        write_table(args.out, df)
    if args.counts:
        print(f"\npixels the remover leaves within {args.band} m of the row's taken ground:")
        cdf = pd.DataFrame(counts, index=CATEGORIES, columns=["ground", "thing", "other"])
        print(cdf.to_string())
        if args.out is not None:
            counts_out = args.out.with_name(args.out.stem + "_counts.csv")
            write_table(counts_out, cdf.rename_axis("category").reset_index())


def _oracle_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--methods", default="flic0,flic6,flic14,bridge,dbscan-fast")
    p.add_argument("--out", type=Path, default=None)
    p.add_argument("--counts", action="store_true")
    p.add_argument("--band", type=float, default=0.05, help="metres, for --counts")


# ---- losses ------------------------------------------------------------------------------------

MIN_POINTS = 100


def majority_clusters(labels: np.ndarray, gt: np.ndarray) -> dict[int, int]:
    """Each thing object (full label, >= MIN_POINTS points) -> its majority cluster (0 = none)."""
    out = {}
    things = thing_mask(gt)
    ids, counts = np.unique(gt[things], return_counts=True)
    for obj in ids[counts >= MIN_POINTS]:
        out[int(obj)] = int(np.bincount(labels[gt == obj]).argmax())
    return out


def merged_pairs(clusters: dict[int, int]) -> set[tuple[int, int]]:
    """Pairs of objects whose majority cluster is the same non-zero cluster."""
    by_cluster: dict[int, list[int]] = {}
    for obj, c in clusters.items():
        if c > 0:
            by_cluster.setdefault(c, []).append(obj)
    return {(a, b) for objs in by_cluster.values() for a in objs for b in objs if a < b}


def losses(args: argparse.Namespace) -> None:
    """Where a clusterer loses IoU in the ground setting: ground left in its clusters, object
    points taken as ground, and objects merged through a few leftover ground points.

    **Per object** (``OUT_objects.csv``): for every ground-truth object (thing classes, >= 100
    points) in the ground setting with the remover, its points, those of its points on pixels
    the remover took as ground (``removed``), the cluster holding most of its points
    (``cluster`` points, ``overlap`` with the object), the ground-class points in that cluster
    (``ground_in_cluster``), the IoU of object and cluster and the IoU the same cluster would
    have without its ground-class points (``iou_without_ground``). This IoU is the object's IoU
    with its majority cluster, a simpler matching than the protocol's one-cluster-one-object
    rule (docs/specification.md), so its mean differs from ``flic evaluate``'s IoU_mu by a few
    tenths.

    **Merged pairs** (``OUT_pairs.csv``): for every frame, the method runs in the no-ground
    setting (ground removed by label) and in the ground setting with the remover. A pair of
    ground-truth objects is *merged only with the remover* when the cluster holding most of each
    object's points is the same cluster in the ground setting but not in the no-ground setting.
    For each such cluster the study counts the points of ground classes that the remover left
    in it and runs the method again with just those points' pixels marked as ground: if the pair
    then separates, those few leftover ground points were the stepping stones that linked the
    two objects.
    """
    cfg = load_config()
    ds = open_dataset(args.data)
    seg_ng = build_segmenter(cfg, args.method, "no-ground")
    seg_g = build_segmenter(cfg, args.method, "ground", args.remover)
    rows = []
    objects = []
    for ref in tqdm(ds.refs(), unit="frame"):
        frame = ds.load(ref)
        prep = prepare(frame, "no-ground", cfg.projection)
        alone = merged_pairs(majority_clusters(seg_ng(prep.image, prep.points)[0], prep.labels))
        prep = prepare(frame, "ground", cfg.projection)
        labels, ground = seg_g.run(prep.image, prep.points)
        clusters = majority_clusters(labels, prep.labels)
        on_ground = ground.on_ground
        ground_class = ground_mask(prep.labels)
        for obj, c in clusters.items():
            points = prep.labels == obj
            cluster = labels == c if c > 0 else np.zeros_like(points)
            n, size = int(points.sum()), int(cluster.sum())
            overlap = int((cluster & points).sum())
            left = int((cluster & ground_class).sum())
            objects.append(
                {
                    "sequence": ref.sequence,
                    "frame": ref.frame,
                    "object": obj,
                    "class": int(semantic(obj)),
                    "points": n,
                    "removed": int((points & on_ground).sum()),
                    "cluster": size,
                    "overlap": overlap,
                    "ground_in_cluster": left,
                    "iou": overlap / (n + size - overlap),
                    "iou_without_ground": overlap / (n + size - left - overlap),
                }
            )
        for a, b in sorted(merged_pairs(clusters) - alone):
            cluster = labels == clusters[a]
            stones = cluster & ground_mask(prep.labels) & (ground.image.point_pixel >= 0)
            mask = ground.mask.copy().reshape(-1)
            mask[ground.image.point_pixel[stones]] = True
            again = seg_g.cluster(
                prep.image,
                prep.points,
                dataclasses.replace(ground, mask=mask.reshape(ground.mask.shape)),
            )
            after = majority_clusters(again, prep.labels)
            rng = np.linalg.norm(prep.points[cluster, :3], axis=1)
            rows.append(
                {
                    "sequence": ref.sequence,
                    "frame": ref.frame,
                    "object_a": a,
                    "object_b": b,
                    "class_a": int(semantic(a)),
                    "class_b": int(semantic(b)),
                    "cluster_points": int(cluster.sum()),
                    "median_range_m": round(float(np.median(rng)), 1),
                    "ground_points_left": int(stones.sum()),
                    "separate_without_them": after[a] != after[b] or after[a] == 0,
                }
            )
    objs = pd.DataFrame(objects)
    write_table(f"{args.out}_objects.csv", objs)
    print(
        f"{args.method} with the {args.remover} remover: IoU with the majority cluster "
        f"{100 * objs.iou.mean():.2f}, {100 * objs.iou_without_ground.mean():.2f} without the "
        f"ground-class points in the clusters ({int(objs.ground_in_cluster.sum())} points in the "
        f"clusters of {int((objs.ground_in_cluster > 0).sum())} of {len(objs)} objects); "
        f"{int(objs.removed.sum())} object points of {int((objs.removed > 0).sum())} objects "
        "taken as ground"
    )
    pairs = pd.DataFrame(rows)
    write_table(f"{args.out}_pairs.csv", pairs)
    n = len(pairs)
    if n:
        sep = int(pairs.separate_without_them.sum())
        print(
            f"{n} object pairs merged only with the {args.remover} remover; {sep} separate when "
            f"the ground points left in their cluster (median {pairs.ground_points_left.median():g}"
            f", range {pairs.ground_points_left.min()}-{pairs.ground_points_left.max()}) are "
            f"removed; median range {pairs.median_range_m.median():g} m -> {args.out}_pairs.csv"
        )
    else:
        print(f"no object pair merged only with the {args.remover} remover -> {args.out}_pairs.csv")


def _losses_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--method", default="bridge")
    p.add_argument("--remover", default="column")
    p.add_argument("--out", type=Path, required=True, help="prefix of the two CSV files")


# ---- heights -----------------------------------------------------------------------------------


def heights(args: argparse.Namespace) -> None:
    """How far a projected pixel's height along its row's elevation is from its nearest point's.

    A projected range image gives every row one elevation (rings: the median of the beam's
    points; spherical: the middle of the bin). A pixel's height "along its row" is
    ``range * sin(elevation)``; its true height is that of its nearest point
    (``RangeImage.point_z``); both as ``column`` sees them
    (:func:`flic_cli.ground.column.pixel_geometry`). For every pixel of the ground setting's
    image (all points projected) this prints, over all frames, the percentiles of the
    difference (true minus row height) and the shares beyond 3 and 8 cm (the ``column``
    remover's bands are 3-8 cm), for all valid pixels and for those whose nearest point has a
    ground class; the horizontal range likewise. Writes one row per pixel set to ``--out``.
    """
    cfg = load_config()
    ds = open_dataset(args.data)
    dz: dict[str, list] = {"all valid pixels": [], "ground-class pixels": []}
    drho: dict[str, list] = {k: [] for k in dz}
    for ref in tqdm(ds.refs(), unit="frame"):
        prep = prepare(ds.load(ref), "ground", cfg.projection)
        image = prep.image
        valid = image.ranges.reshape(-1) > 0
        true_rho, true_z = (a.reshape(-1) for a in pixel_geometry(image, exact=True)[:2])
        row_rho, row_z = (a.reshape(-1) for a in pixel_geometry(image, exact=False)[:2])
        owner = pixel_owners(image, prep.points)
        on_ground = np.zeros_like(valid)
        on_ground[valid] = ground_mask(prep.labels)[owner[valid]]
        for name, sel in (("all valid pixels", valid), ("ground-class pixels", on_ground)):
            dz[name].append(true_z[sel] - row_z[sel])
            drho[name].append(true_rho[sel] - row_rho[sel])
    rows = []
    for name in dz:
        z = np.concatenate(dz[name])
        r = np.concatenate(drho[name])
        p1, p10, p50, p90, p99 = np.percentile(z, [1, 10, 50, 90, 99])
        rows.append(
            {
                "pixels": name,
                "count": z.size,
                "dz_p1_cm": round(100 * p1, 1),
                "dz_p10_cm": round(100 * p10, 1),
                "dz_median_cm": round(100 * p50, 1),
                "dz_p90_cm": round(100 * p90, 1),
                "dz_p99_cm": round(100 * p99, 1),
                "share_dz_over_3cm": round(float(np.mean(np.abs(z) > 0.03)), 3),
                "share_dz_over_8cm": round(float(np.mean(np.abs(z) > 0.08)), 3),
                "drho_p1_cm": round(100 * float(np.percentile(r, 1)), 1),
                "drho_p99_cm": round(100 * float(np.percentile(r, 99)), 1),
            }
        )
    out = pd.DataFrame(rows)
    write_table(args.out, out)
    print(out.to_string(index=False))


def _heights_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=Path, default=Path("results/ground/pixel_heights.csv"))


# ---- figure ------------------------------------------------------------------------------------


def figure(args: argparse.Namespace) -> None:
    """Figure: one labelled frame seen from above, two removers' ground masks side by side.

    Every point of the frame is drawn from above (x forward, y left, metres, within
    ``--extent`` of the sensor), coloured by what each remover made of it: taken as ground
    (light grey), kept (dark grey), and the two errors that cost IoU: points of ground-truth
    objects taken as ground (red) and ground-class points left beside the objects (orange).
    The title of each panel gives the remover's ground recall and the share of object points it
    removed in this frame.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cfg = load_config()
    ds = open_dataset(args.data)
    ref = next(
        r for r in ds.refs() if r.sequence == args.sequence and r.frame == args.frame
    )  # fmt: skip
    prep = prepare(ds.load(ref), "ground", cfg.projection)
    pts, labels = prep.points, prep.labels
    is_ground, is_thing = ground_mask(labels), thing_mask(labels)
    inside = (np.abs(pts[:, 0]) < args.extent) & (np.abs(pts[:, 1]) < args.extent)
    names = args.removers.split(",")
    fig, axes = plt.subplots(1, len(names), figsize=(7 * len(names), 7.4), squeeze=False)
    for ax, name in zip(axes[0], names, strict=True):
        remover = cfg.remover(name)
        taken = point_ground(prep.image, remover.extract(prep.image, pts).mask)
        counts = ground_counts(labels, taken)
        layers = [
            (taken & ~(is_thing), "#d9d9d9", 0.4, "taken as ground"),
            (~taken & ~is_ground, "#505050", 0.6, "kept"),
            (~taken & is_ground, "#ff9900", 1.2, "ground-class point left"),
            (taken & is_thing, "#e00000", 3.0, "object point taken as ground"),
        ]
        for mask, colour, size, label in layers:
            m = mask & inside
            ax.scatter(pts[m, 1], pts[m, 0], s=size, c=colour, linewidths=0, label=label)
        ax.set_title(
            f"{name}: ground recall {100 * counts.recall:.1f} %, "
            f"object points removed {100 * counts.things_removed_share:.1f} %"
        )
        ax.set_xlim(args.extent, -args.extent)  # y to the left, as seen from above
        ax.set_ylim(-args.extent, args.extent)
        ax.set_aspect("equal")
        ax.set_xlabel("y (m, left)")
        ax.set_ylabel("x (m, forward)")
        ax.legend(loc="lower left", markerscale=6, fontsize=8)
    fig.suptitle(
        f"SemanticKITTI sequence {ref.sequence} frame {ref.frame:06d}, ground setting "
        "(all points); KITTI scans: Geiger et al. 2012, labels: Behley et al. 2019"
    )
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


def _figure_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--sequence", default="08")
    p.add_argument("--frame", type=int, default=0)
    p.add_argument("--removers", default="paper,column")
    p.add_argument("--extent", type=float, default=30.0, help="metres around the sensor")
    p.add_argument("--out", type=Path, default=Path("results/ground/ground_masks.png"))


# ---- the command line --------------------------------------------------------------------------

STUDIES: Studies = {
    "table": (table, _table_arguments),
    "speed": (speed, _speed_arguments),
    "sweep": (sweep, _sweep_arguments),
    "oracle": (oracle, _oracle_arguments),
    "losses": (losses, _losses_arguments),
    "heights": (heights, _heights_arguments),
    "figure": (figure, _figure_arguments),
}


def _data_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", nargs="?", default=SHARED, type=Path, help=f"default {SHARED}")


def main(argv: list[str] | None = None) -> None:
    run_studies(__doc__, STUDIES, argv, common=_data_argument)


if __name__ == "__main__":
    main()
