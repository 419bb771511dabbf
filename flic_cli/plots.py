"""Pictures people would rather look at than read. matplotlib is imported lazily (Agg backend)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flic_cli.classes import ground_mask, thing_mask
from flic_cli.io.atomic import atomic_write
from flic_cli.metrics import MIN_FRAGMENT_POINTS, MIN_OBJECT_POINTS, ObjectMatches, match_objects
from flic_cli.range_image import RangeImage


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: Path) -> None:
    """Write a figure atomically (temporary name, then rename) and close it."""
    plt = _pyplot()
    with atomic_write(path) as tmp:
        fmt = Path(path).suffix.lstrip(".") or "png"
        fig.savefig(tmp, dpi=120, bbox_inches="tight", format=fmt)
    plt.close(fig)


def cluster_colours(n: int, seed: int = 7) -> np.ndarray:
    """(n + 1, 3) RGB in [0, 1]: index 0 black (empty), then distinct random bright colours."""
    rng = np.random.default_rng(seed)
    import colorsys

    hues = rng.permutation(n) / max(n, 1)
    cols = [colorsys.hsv_to_rgb(h, 0.75 + 0.25 * rng.random(), 0.95) for h in hues]
    return np.vstack([[0.0, 0.0, 0.0], *cols]) if n else np.zeros((1, 3))


#: Colours of the range-image render (RGB in [0, 1]).
RENDER_GROUND = (0.6, 0.6, 0.6)
RENDER_UNCLUSTERED = (0.25, 0.25, 0.25)
RENDER_EMPTY = (0.0, 0.0, 0.0)


def render_segmentation(
    image: RangeImage,
    point_labels: np.ndarray,
    ground: np.ndarray | None,
    path: Path,
    title: str = "",
) -> None:
    """PNG of the range image coloured by cluster, with a legend of the colours.

    Clusters get bright colours; ground pixels :data:`RENDER_GROUND` (light grey), measured
    pixels in no cluster :data:`RENDER_UNCLUSTERED` (dark grey), pixels without a measurement
    :data:`RENDER_EMPTY` (black). The legend below the image names each of them.

    Parameters
    ----------
    image : the range image the labels were computed on.
    point_labels : (N,) labels of the image's points (0 = none).
    ground : (H, W) ground mask or None.
    path : output PNG.
    title : figure title; default: the number of clusters.
    """
    from matplotlib.patches import Patch

    plt = _pyplot()
    h, w = image.shape
    pix = image.pixel_values(np.asarray(point_labels, dtype=np.int64))
    k = int(pix.max())
    rgb = cluster_colours(k)[pix]
    valid = image.valid
    rgb[~valid] = RENDER_EMPTY
    rgb[valid & (pix == 0)] = RENDER_UNCLUSTERED
    if ground is not None:
        rgb[ground & valid] = RENDER_GROUND
    fig, ax = plt.subplots(figsize=(min(24, w / 60), max(2.5, h / 60 * 2.2)))
    ax.imshow(rgb, aspect="auto", interpolation="nearest")
    ax.set_xlabel("column (azimuth +180 deg ... -180 deg)")
    ax.set_ylabel("row (beam, top first)")
    ax.set_title(title or f"{k} clusters")
    shown = cluster_colours(max(k, 3))[1:4]
    handles = [
        Patch(facecolor=RENDER_GROUND, edgecolor="0.3", label="ground"),
        Patch(facecolor=RENDER_UNCLUSTERED, edgecolor="0.3", label="no cluster"),
        Patch(facecolor=RENDER_EMPTY, edgecolor="0.3", label="no measurement"),
        tuple(Patch(facecolor=c) for c in shown),
    ]
    labels = ["ground", "measured, in no cluster", "no measurement", "clusters (one colour each)"]
    if ground is None:
        handles, labels = handles[1:], labels[1:]
    from matplotlib.legend_handler import HandlerTuple

    ax.legend(
        handles,
        labels,
        loc="upper center",
        ncol=len(handles),
        bbox_to_anchor=(0.5, -0.2),
        frameon=False,
        handler_map={tuple: HandlerTuple(ndivide=None, pad=0)},
    )
    save_figure(fig, path)


# ---- flic benchmark (paper Fig. 9 and 10) ----------------------------------------------------


def plot_runtime_series(
    series: dict[str, tuple[np.ndarray, np.ndarray]], path: Path, title: str = ""
) -> None:
    """Per-frame runtime over the log, log scale (paper Fig. 9).

    Parameters
    ----------
    series : method -> (frame indices, milliseconds).
    path : output PNG.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(12, 4.5))
    for name, (x, ms) in series.items():
        sparse = len(x) > 1 and np.median(np.diff(x)) > 1
        ax.plot(x, ms, lw=0.8, marker="o" if sparse or len(x) < 50 else None, ms=3, label=name)
    ax.set_yscale("log")
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.set_xlabel("frame (position in the log)")
    ax.set_ylabel("runtime per frame [ms]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small")
    ax.set_title(title)
    save_figure(fig, path)


def plot_hz_boxplot(hz: dict[str, np.ndarray], path: Path, title: str = "") -> None:
    """Box plot of the per-frame rate in Hz, one box per method (paper Fig. 10).

    The box spans the 25th to 75th percentile of the frames (line: median), the whiskers reach
    the furthest frame within 1.5 box lengths of the box, dots are frames beyond (matplotlib's
    default Tukey box plot); a caption under the plot says so, and each tick label gives the
    number of frames.

    Parameters
    ----------
    hz : method -> per-frame rates (1000 / milliseconds).
    path : output PNG.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(max(5, 1.3 * len(hz) + 2), 4.8))
    ax.boxplot(list(hz.values()), whis=1.5, showfliers=True, flierprops={"markersize": 2})
    ax.set_xticks(
        range(1, len(hz) + 1),
        [f"{m}\n(n={len(v)})" for m, v in hz.items()],
        rotation=30,
        ha="right",
    )
    ax.set_yscale("log")
    ax.set_ylabel("frame rate [Hz]")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.set_title(title)
    fig.text(
        0.01,
        -0.02,
        "box: 25th-75th percentile of the frames, line: median; whiskers: furthest frame within "
        "1.5 box lengths of the box; dots: frames beyond the whiskers. n = frames.",
        fontsize=8,
        va="top",
        wrap=True,
    )
    save_figure(fig, path)


def plot_runtime_histogram(
    counts: dict[str, np.ndarray], edges: np.ndarray, path: Path, title: str = ""
) -> None:
    """Runtime histograms on shared log-spaced bins, one panel per method (small multiples).

    Every method has its own row, all rows share the x axis (same bins, same range), so no
    method's histogram hides another's.

    Parameters
    ----------
    counts : method -> frames per bin (``len(edges) - 1`` values).
    edges : bin edges in milliseconds.
    path : output PNG.
    """
    plt = _pyplot()
    names = list(counts) or [""]
    fig, axes = plt.subplots(
        len(names), 1, figsize=(10, 1.0 + 0.85 * len(names)), sharex=True, squeeze=False
    )
    used = np.flatnonzero(np.sum(list(counts.values()), axis=0)) if counts else np.array([0])
    if used.size == 0:
        used = np.array([0])
    lo, hi = max(used.min() - 1, 0), min(used.max() + 2, len(edges) - 1)
    for i, (ax, name) in enumerate(zip(axes[:, 0], names, strict=True)):
        c = np.asarray(counts.get(name, np.zeros(len(edges) - 1)))
        ax.stairs(c, edges, fill=True, color=f"C{i % 10}", alpha=0.8)
        ax.set_ylim(0, max(1, c.max()) * 1.15)
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize="small")
        ax.tick_params(axis="y", labelsize="x-small")
        ax.grid(True, axis="x", which="both", alpha=0.3)
    ax = axes[-1, 0]
    ax.set_xscale("log")
    ax.set_xlim(edges[lo], edges[hi])
    ax.set_xlabel("runtime per frame [ms]")
    fig.supylabel("frames per bin", fontsize="small")
    axes[0, 0].set_title(title)
    save_figure(fig, path)


def plot_sweep(
    values: np.ndarray,
    iou_mu: np.ndarray,
    p_mu: np.ndarray,
    best: int,
    path: Path,
    xlabel: str,
    title: str = "",
) -> None:
    """The parameter study curve (paper Fig. 8): IoU_mu and P_mu against a parameter.

    Parameters
    ----------
    values : (K,) parameter values.
    iou_mu, p_mu : (K,) scores in percent.
    best : index of the best value, marked with a dashed line and its IoU_mu.
    path : output PNG (written atomically).
    xlabel : x axis label, with units.
    title : figure title.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    ax.plot(values, iou_mu, "o-", ms=3, color="C0", label="IoU$_\\mu$")
    ax.plot(values, p_mu, "s:", ms=3, color="C1", label="P$_\\mu$")
    if len(values):
        bx, by = float(values[best]), float(iou_mu[best])
        ax.axvline(bx, color="0.3", ls="--", lw=1)
        ax.annotate(
            f"best {bx:g}: IoU$_\\mu$ {by:.2f}%",
            xy=(bx, by),
            xytext=(8, -16),
            textcoords="offset points",
            fontsize=9,
        )
    ax.set_xlabel(xlabel)
    ax.set_ylabel("score [%]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best")
    if title:
        ax.set_title(title, fontsize=10)
    save_figure(fig, path)


# ---- a frame in 3D: bird's-eye and oblique views (issue 10) ---------------------------------

#: Point colours of the frame views (RGB in [0, 1]).
VIEW_GROUND = (0.78, 0.78, 0.78)
VIEW_OTHER = (0.35, 0.35, 0.35)
#: Box colours of the marked objects and clusters.
MARK_COLOURS: dict[str, str] = {"missed": "red", "split": "darkorange", "merged": "magenta"}


@dataclass(frozen=True)
class ObjectMarks:
    """Which objects a segmentation missed or split and which clusters merged objects.

    Attributes
    ----------
    matches : ObjectMatches
        :func:`flic_cli.metrics.match_objects` of the frame (one entry per evaluated object).
    missed : numpy.ndarray
        ``uint32`` labels of the objects with no matched cluster (``matches.cluster == -1``).
    split : numpy.ndarray
        ``uint32`` labels of the objects spread over >= 2 clusters holding at least
        ``min_fragment_points`` of their points each (``n_fragments >= 2``).
    merged : numpy.ndarray
        ``int64`` ids of the clusters holding at least ``min_fragment_points`` points of each of
        >= 2 objects.
    """

    matches: ObjectMatches
    missed: np.ndarray
    split: np.ndarray
    merged: np.ndarray


def object_marks(
    gt_labels: np.ndarray,
    pred: np.ndarray,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> ObjectMarks:
    """Missed, split and merged objects of one frame, by the paper's protocol.

    The counts agree with :func:`flic_cli.metrics.segmentation_stats` (``over_segmented`` =
    ``len(split)``, ``under_segmented`` = ``len(merged)``).

    Parameters
    ----------
    gt_labels : (N,) uint32 SemanticKITTI labels of the evaluated point set.
    pred : (N,) cluster ids, values <= 0 = unclustered.
    min_points : objects with fewer points are not evaluated (100).
    min_fragment_points : shared points from which a cluster and an object touch (10).
    """
    matches = match_objects(gt_labels, pred, None, min_points, min_fragment_points)
    gt = np.asarray(gt_labels).astype(np.uint32, copy=False)
    p = np.asarray(pred).astype(np.int64, copy=False)
    in_obj = np.isin(gt, matches.label) & thing_mask(gt) & (p > 0)
    pairs, shared = np.unique(
        np.stack([gt[in_obj].astype(np.int64), p[in_obj]], axis=1), axis=0, return_counts=True
    )
    touching = pairs[shared >= min_fragment_points]
    clusters, n_objects = np.unique(touching[:, 1], return_counts=True)
    return ObjectMarks(
        matches=matches,
        missed=matches.label[matches.cluster < 0],
        split=matches.label[matches.n_fragments >= 2],
        merged=clusters[n_objects >= 2].astype(np.int64),
    )


def _box_edges(lo: np.ndarray, hi: np.ndarray) -> list[np.ndarray]:
    """The 12 edges of an axis-aligned box as (2, 3) arrays."""
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
    pts = lo + corners * (hi - lo)
    return [
        pts[[a, b]]
        for a in range(8)
        for b in range(a + 1, 8)
        if np.count_nonzero(corners[a] != corners[b]) == 1
    ]


def render_frame_views(
    path: Path,
    points: np.ndarray,
    pred: np.ndarray,
    gt_labels: np.ndarray | None = None,
    ground: np.ndarray | None = None,
    title: str = "",
    extent_m: float = 40.0,
    min_points: int = MIN_OBJECT_POINTS,
    min_fragment_points: int = MIN_FRAGMENT_POINTS,
) -> dict[str, int]:
    """Bird's-eye and oblique 3D views of a frame's points coloured by cluster (PNG).

    Without labels: one row, the prediction from above and from an oblique viewpoint. With
    labels: the ground truth (left column) beside the prediction (right column), and boxes around
    the missed (red), split (orange) objects and the merged (magenta) clusters of
    :func:`object_marks`, in every view. Colours: clusters by id (as in the PLY export,
    :func:`flic_cli.io.ply.cluster_rgb`); a found object in the ground truth gets the colour of
    its cluster, a missed object a colour of its own; ground light grey; unclustered points (and
    ground-truth points of no evaluated object) dark grey. Only points within ``extent_m`` of the
    sensor in x and y are drawn.

    Parameters
    ----------
    path : output PNG (written atomically).
    points : (N, 3) points in metres, sensor frame (x forward, y left, z up).
    pred : (N,) cluster ids, values <= 0 = unclustered.
    gt_labels : (N,) uint32 SemanticKITTI labels, or None.
    ground : (N,) bool, the points the ground remover took, or None.
    title : figure title (the counts are added below it).
    extent_m : half-width of the square drawn, metres.
    min_points, min_fragment_points : as in :func:`object_marks`.

    Returns
    -------
    dict of str to int
        ``clusters``, and with labels ``objects``, ``missed``, ``split``, ``merged``.
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    from flic_cli.io.ply import cluster_rgb

    plt = _pyplot()
    pts = np.asarray(points, dtype=np.float64)[:, :3]
    p = np.asarray(pred).astype(np.int64)
    n = pts.shape[0]
    if p.shape != (n,):
        raise ValueError(f"pred must have shape ({n},), got {p.shape}")
    g = np.zeros(n, bool) if ground is None else np.asarray(ground, dtype=bool)

    pred_rgb = cluster_rgb(np.maximum(p, 0)).astype(np.float64) / 255
    pred_rgb[p <= 0] = VIEW_OTHER
    pred_rgb[g] = VIEW_GROUND
    counts = {"clusters": int(np.unique(p[p > 0]).size)}
    panels = [("prediction", pred_rgb)]
    boxes: list[tuple[str, np.ndarray]] = []  # (kind, point mask)
    if gt_labels is not None:
        gt = np.asarray(gt_labels).astype(np.uint32)
        marks = object_marks(gt, p, min_points, min_fragment_points)
        m = marks.matches
        gt_rgb = np.tile(np.array(VIEW_OTHER), (n, 1))
        gt_rgb[ground_mask(gt)] = VIEW_GROUND
        obj_index = np.searchsorted(m.label, gt)
        is_obj = thing_mask(gt) & np.isin(gt, m.label)
        colour_ids = np.where(m.cluster >= 0, m.cluster, 1_000_003 + np.arange(len(m)))
        gt_rgb[is_obj] = cluster_rgb(colour_ids[obj_index[is_obj]]) / 255
        panels.insert(0, ("ground truth", gt_rgb))
        boxes += [("missed", gt == lab) for lab in marks.missed]
        boxes += [("split", gt == lab) for lab in marks.split]
        boxes += [("merged", p == c) for c in marks.merged]
        counts.update(
            objects=len(m),
            missed=int(marks.missed.size),
            split=int(marks.split.size),
            merged=int(marks.merged.size),
        )

    inside = (np.abs(pts[:, 0]) <= extent_m) & (np.abs(pts[:, 1]) <= extent_m)
    order = np.flatnonzero(inside)
    order = order[np.argsort(~g[order], kind="stable")]  # ground first, objects drawn on top
    z_lo, z_hi = -3.0, 5.0
    fig = plt.figure(figsize=(7.5 * len(panels), 12.5))
    grid = fig.add_gridspec(2, len(panels), height_ratios=(1.0, 0.75), hspace=0.14)
    for col, (name, rgb) in enumerate(panels):
        ax = fig.add_subplot(grid[0, col])
        ax.scatter(pts[order, 0], pts[order, 1], c=rgb[order], s=0.6, lw=0, rasterized=True)
        ax.plot(0, 0, marker="^", color="black", ms=6)
        ax.set_xlim(-extent_m, extent_m)
        ax.set_ylim(-extent_m, extent_m)
        ax.set_aspect("equal")
        ax.set_xlabel("x (forward) [m]")
        ax.set_ylabel("y (left) [m]")
        ax.set_title(f"{name}, bird's-eye view")
        ax3 = fig.add_subplot(grid[1, col], projection="3d")
        ax3.scatter(
            pts[order, 0], pts[order, 1], pts[order, 2], c=rgb[order], s=0.5, lw=0,
            depthshade=False, rasterized=True,
        )  # fmt: skip
        ax3.set_xlim(-extent_m, extent_m)
        ax3.set_ylim(-extent_m, extent_m)
        ax3.set_zlim(z_lo, z_hi)
        # Heights drawn at twice their scale, so that objects stand out from the ground.
        ax3.set_box_aspect((1, 1, 2 * (z_hi - z_lo) / (2 * extent_m)), zoom=1.35)
        ax3.view_init(elev=32, azim=-140)
        ax3.set_zticks([-2, 0, 2, 4])
        ax3.tick_params(labelsize=7, pad=0)
        for axis in (ax3.xaxis, ax3.yaxis, ax3.zaxis):
            axis.pane.set_visible(False)
        ax3.set_xlabel("x [m]", fontsize=8, labelpad=-2)
        ax3.set_ylabel("y [m]", fontsize=8, labelpad=-2)
        ax3.set_zlabel("z [m]", fontsize=8, labelpad=-4)
        ax3.set_title(f"{name}, oblique view (heights x2)", y=0.93)
        for kind, mask in boxes:
            sel = mask & inside
            if not sel.any():
                continue
            lo, hi = pts[sel].min(axis=0) - 0.3, pts[sel].max(axis=0) + 0.3
            colour = MARK_COLOURS[kind]
            ax.add_patch(Rectangle(lo[:2], *(hi - lo)[:2], fill=False, ec=colour, lw=1.2, ls="--"))
            ax.annotate(kind, (lo[0], hi[1]), color=colour, fontsize=7, va="bottom")
            for edge in _box_edges(lo, hi):
                ax3.plot(*edge.T, color=colour, lw=0.9)
    handles = [
        Patch(facecolor=VIEW_GROUND, label="ground"),
        Patch(facecolor=VIEW_OTHER, label="no cluster / no evaluated object"),
        Patch(facecolor=cluster_rgb(np.array([1]))[0] / 255, label="a cluster (colour per id)"),
    ]
    if gt_labels is not None:
        handles += [
            Line2D(
                [], [], color=c, ls="--", label=f"{k} {'cluster' if k == 'merged' else 'object'}"
            )
            for k, c in MARK_COLOURS.items()
        ]
    fig.legend(
        handles=handles,
        loc="lower center",
        ncol=len(handles),
        frameon=False,
        bbox_to_anchor=(0.5, 0.06 if len(panels) > 1 else 0.0),
    )
    summary = f"{counts['clusters']} clusters"
    if gt_labels is not None:
        summary += (
            f"; {counts['objects']} objects of >= {min_points} points: {counts['missed']} missed, "
            f"{counts['split']} split, {counts['merged']} merged clusters"
        )
    fig.suptitle(f"{title}\n{summary}" if title else summary)
    save_figure(fig, path)
    return counts


# ---- choosing a method (issue 7) -----------------------------------------------------------


def plot_quality_speed(
    methods: Sequence[str],
    ms_median: np.ndarray,
    iou_mu: np.ndarray,
    path: Path,
    iou_low: np.ndarray | None = None,
    iou_high: np.ndarray | None = None,
    title: str = "",
) -> None:
    """Quality against speed: IoU_mu (with its interval) against median ms per frame.

    One labelled point per method, log x axis; better methods lie towards the top left.

    Parameters
    ----------
    methods : method names.
    ms_median : (M,) median runtime per frame, milliseconds (> 0).
    iou_mu : (M,) IoU_mu, percent.
    path : output PNG (written atomically).
    iou_low, iou_high : (M,) bounds of the 95% interval of IoU_mu, percent, or None (no error
        bars); NaN bounds draw no bar for that method.
    title : figure title.
    """
    plt = _pyplot()
    names = list(methods)
    x = np.asarray(ms_median, dtype=np.float64)
    y = np.asarray(iou_mu, dtype=np.float64)
    if x.shape != (len(names),) or y.shape != (len(names),):
        raise ValueError("methods, ms_median and iou_mu must have one entry per method")
    if (x <= 0).any():
        raise ValueError("median runtimes must be > 0 ms for a log axis")
    fig, ax = plt.subplots(figsize=(7.5, 5))
    for i, name in enumerate(names):
        yerr = None
        if iou_low is not None and iou_high is not None:
            lo, hi = float(np.asarray(iou_low)[i]), float(np.asarray(iou_high)[i])
            if np.isfinite(lo) and np.isfinite(hi):
                yerr = [[y[i] - lo], [hi - y[i]]]
        ax.errorbar(x[i], y[i], yerr=yerr, fmt="o", color=f"C{i % 10}", capsize=4, ms=6, label=name)
        ax.annotate(name, (x[i], y[i]), xytext=(6, 5), textcoords="offset points", fontsize=9)
    ax.set_xscale("log")
    lo_x, hi_x = x.min(), x.max()
    ax.set_xlim(lo_x / 1.6, hi_x * 2.2)
    ax.set_xlabel("median runtime per frame [ms] (log scale)")
    bars = " (bars: 95% bootstrap interval over frames)" if iou_low is not None else ""
    ax.set_ylabel("IoU$_\\mu$ [%]" + bars)
    ax.grid(True, which="both", alpha=0.3)
    if title:
        ax.set_title(title, fontsize=10)
    save_figure(fig, path)
