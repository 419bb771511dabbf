"""The clusterers. To add a method: a frozen dataclass with ``segment(image, points, ground)``
(see :class:`flic_cli.methods.base.Method`) registered in ``KINDS`` under the ``kind`` name that
config files use."""

from flic_cli.methods.base import Method, drop_small, pixel_point_counts
from flic_cli.methods.bogoslavskyi import Bogoslavskyi, bogoslavskyi_labels
from flic_cli.methods.bridge import Bridge, bridge_labels
from flic_cli.methods.dbscan import Dbscan, dbscan_labels
from flic_cli.methods.flic import Flic, flic_labels

KINDS: dict[str, type] = {
    "flic": Flic,
    "bogoslavskyi": Bogoslavskyi,
    "dbscan": Dbscan,
    "bridge": Bridge,
}

__all__ = [
    "KINDS",
    "Bogoslavskyi",
    "Bridge",
    "Dbscan",
    "Flic",
    "Method",
    "bogoslavskyi_labels",
    "bridge_labels",
    "dbscan_labels",
    "drop_small",
    "flic_labels",
    "pixel_point_counts",
]
