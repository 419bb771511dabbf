"""The projection step: a SemanticKITTI scan into the range image that every image method sees.

:class:`Projection` is the component (its fields are the ``[projection]`` table of a config);
the work is done by :func:`flic_cli.range_image.project_points`. Moosmann logs come as range
images already and are not projected.
"""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator
from pydantic.dataclasses import dataclass

from flic_cli.config.component import STRICT
from flic_cli.range_image import RangeImage, project_points


@dataclass(frozen=True, config=STRICT)
class Projection:
    """How a scan becomes a range image (SPEC section 2).

    Attributes
    ----------
    mode : ``"rings"``: rows recovered from the scan order (falls back to spherical, with a
        warning naming the scan, when the scan is not in sensor order); ``"spherical"``: uniform
        elevation bins over ``[fov_down_deg, fov_up_deg]``.
    width : columns over 360 degrees.
    rows : beams (rows of the image).
    fov_up_deg, fov_down_deg : vertical field of view of the spherical projection, degrees.
    """

    mode: Literal["rings", "spherical"] = "rings"
    width: Annotated[int, Field(ge=8, le=65536, description="columns over 360 deg")] = 2048
    rows: Annotated[int, Field(ge=1, le=1024, description="beams")] = 64
    fov_up_deg: Annotated[float, Field(gt=-90, lt=90, description="degrees")] = 3.0
    fov_down_deg: Annotated[float, Field(gt=-90, lt=90, description="degrees")] = -25.0

    @model_validator(mode="after")
    def _fov_order(self) -> Projection:
        if self.fov_up_deg <= self.fov_down_deg:
            raise ValueError(
                f"fov_up_deg ({self.fov_up_deg}) must be above fov_down_deg ({self.fov_down_deg})"
            )
        return self

    def __call__(self, points: np.ndarray, keep: np.ndarray | None = None) -> RangeImage:
        """The range image of ``points`` (see :func:`flic_cli.range_image.project_points`)."""
        return project_points(
            points,
            width=self.width,
            mode=self.mode,
            rows=self.rows,
            fov_up_deg=self.fov_up_deg,
            fov_down_deg=self.fov_down_deg,
            keep=keep,
        )
