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
        fig.savefig(tmp, dpi=120, bbox_inches="tight", format=Path(path).suffix.lstrip(".") or "png")
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
