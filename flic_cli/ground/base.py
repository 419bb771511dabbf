"""The one interface every ground remover implements: range image in, ground mask out."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from flic_cli.range_image import RangeImage


class GroundRemover(Protocol):
    """A ground remover: a component (see :mod:`flic_cli.config.component`) called on a range
    image and the scan's points; returns the (H, W) bool mask of its ground pixels (empty pixels
    are never ground).

    ``points`` are the (N, 3) points of the evaluated point set, point i in pixel
    ``image.point_pixel[i]``; removers that work on the image alone ignore them.
    """

    def __call__(self, image: RangeImage, points: np.ndarray) -> np.ndarray: ...
