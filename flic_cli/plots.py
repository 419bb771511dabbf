"""Pictures people would rather look at than read. matplotlib is imported lazily (Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flic_cli.io.atomic import atomic_write
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


def render_segmentation(
    image: RangeImage,
    point_labels: np.ndarray,
    ground: np.ndarray | None,
    path: Path,
    title: str = "",
) -> None:
    """PNG of the range image coloured by cluster: ground grey, unclustered dark grey, empty black.

    Parameters
    ----------
    image : the range image the labels were computed on.
    point_labels : (N,) labels of the image's points (0 = none).
    ground : (H, W) ground mask or None.
    path : output PNG.
    """
    plt = _pyplot()
    h, w = image.shape
    pix = np.zeros(h * w, dtype=np.int64)
    has = image.point_pixel >= 0
    pix[image.point_pixel[has]] = point_labels[has]
    pix = pix.reshape(h, w)
    k = int(pix.max())
    rgb = cluster_colours(k)[pix]
    valid = image.valid
    rgb[valid & (pix == 0)] = (0.25, 0.25, 0.25)
    if ground is not None:
        rgb[ground & valid] = (0.6, 0.6, 0.6)
    fig, ax = plt.subplots(figsize=(min(24, w / 60), max(2.5, h / 60 * 2.2)))
    ax.imshow(rgb, aspect="auto", interpolation="nearest")
    ax.set_xlabel("column (azimuth +180 deg ... -180 deg)")
    ax.set_ylabel("row (beam, top first)")
    ax.set_title(title or f"{k} clusters; grey = ground, dark grey = unclustered")
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

    Parameters
    ----------
    hz : method -> per-frame rates (1000 / milliseconds).
    path : output PNG.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(max(5, 1.3 * len(hz) + 2), 4.5))
    ax.boxplot(list(hz.values()), showfliers=True, flierprops={"markersize": 2})
    ax.set_xticks(range(1, len(hz) + 1), list(hz), rotation=30, ha="right")
    ax.set_yscale("log")
    ax.set_ylabel("frame rate [Hz]")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.set_title(title)
    save_figure(fig, path)


def plot_runtime_histogram(
    counts: dict[str, np.ndarray], edges: np.ndarray, path: Path, title: str = ""
) -> None:
    """Runtime histograms on shared log-spaced bins, one step line per method.

    Parameters
    ----------
    counts : method -> frames per bin (``len(edges) - 1`` values).
    edges : bin edges in milliseconds.
    path : output PNG.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(10, 4.5))
    used = np.flatnonzero(np.sum(list(counts.values()), axis=0)) if counts else np.array([0])
    lo, hi = max(used.min() - 1, 0), min(used.max() + 2, len(edges) - 1)
    for name, c in counts.items():
        ax.stairs(c, edges, label=name)
    ax.set_xscale("log")
    ax.set_xlim(edges[lo], edges[hi])
    ax.set_xlabel("runtime per frame [ms]")
    ax.set_ylabel("frames")
    ax.legend(fontsize="small")
    ax.set_title(title)
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
