"""Ground extraction: the step between the range image and the clusterer.

Every remover is a function ``(RangeImage, **params) -> (H, W) bool`` (True = ground pixel):

- :func:`paper_ground` -- the FLIC paper's tan(beta) test with the height image (SPEC section 3);
- :func:`bogoslavskyi_ground` -- Bogoslavskyi & Stachniss' angle image, Savitzky-Golay smoothing
  and breadth-first growth from the lowest row;
- "No Ground" setting: points of the ground classes are removed by label before projection
  (:func:`flic_cli.classes.ground_mask`), so no remover runs.
"""

from flic_cli.ground.bogoslavskyi import bogoslavskyi_ground
from flic_cli.ground.paper import paper_ground

REMOVERS = {"paper": paper_ground, "bogoslavskyi": bogoslavskyi_ground}

__all__ = ["REMOVERS", "bogoslavskyi_ground", "paper_ground"]
