"""Ground extraction: the step between the range image and the clusterer.

Every remover is a component (:mod:`flic_cli.component`) with one method,
``remover.extract(image, points) -> Ground`` (:class:`flic_cli.ground.base.Ground`: the ground
pixels, the decision per point where it makes one, the held cells and the image the clusterers
see), see :class:`flic_cli.ground.base.GroundRemover`:

- ``paper`` -- :class:`PaperGround`, the FLIC paper's tan(beta) test with the height image;
- ``bogoslavskyi`` -- :class:`BogoslavskyiGround`, Bogoslavskyi & Stachniss' angle image,
  Savitzky-Golay smoothing and breadth-first growth from the lowest row;
- ``column`` -- :class:`ColumnGround`, flic's own: column-wise ground tracking with a local
  ground-height model, which keeps the points of objects;
- ``patchworkpp`` -- :class:`PatchworkppGround`, Patchwork++ on the scan's points (optional extra
  ``flic[patchworkpp]``);
- the "No Ground" setting removes the ground classes' points by label before projection
  (:func:`flic_cli.classes.ground_mask`), so no remover runs.

A remover that decides per pixel returns :meth:`flic_cli.ground.base.Ground.from_mask`; ``column``
also decides per point (the points hidden behind their pixel's nearest point on a projected scan)
and holds cells out of the clustering that join the cluster standing on them afterwards (the feet
of things). Every clusterer takes the :class:`~flic_cli.ground.base.Ground` as it is.

To add a remover: a component class with ``extract(image, points) -> Ground``, named in
:data:`flic_cli.registry.REMOVERS` under the name that ``[ground.NAME]`` config tables and
``--ground-remover`` use.
"""

from flic_cli.ground.base import (
    Ground,
    GroundRemover,
    extract_ground,
    pixel_mask,
    pixel_owners,
)
from flic_cli.ground.bogoslavskyi import BogoslavskyiGround, bogoslavskyi_ground
from flic_cli.ground.column import ColumnGround
from flic_cli.ground.paper import PaperGround, paper_ground
from flic_cli.ground.patchworkpp import PatchworkppGround
from flic_cli.registry import REMOVERS as _REMOVERS
from flic_cli.registry import load_all

#: Ground remover classes by name (from :data:`flic_cli.registry.REMOVERS`).
REMOVERS: dict[str, type] = load_all(_REMOVERS)

__all__ = [
    "REMOVERS",
    "BogoslavskyiGround",
    "ColumnGround",
    "Ground",
    "GroundRemover",
    "PaperGround",
    "PatchworkppGround",
    "bogoslavskyi_ground",
    "extract_ground",
    "paper_ground",
    "pixel_mask",
    "pixel_owners",
]
