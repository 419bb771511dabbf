"""The clusterers. To add a method: a component class with ``segment(image, points, ground)``
(see :class:`flic_cli.methods.base.Method` and :mod:`flic_cli.component`), named in
:data:`flic_cli.registry.METHODS` under the ``kind`` that config files use."""

from flic_cli.methods.base import Method, drop_small
from flic_cli.methods.bogoslavskyi import Bogoslavskyi, bogoslavskyi_labels
from flic_cli.methods.bridge import Bridge, bridge_labels
from flic_cli.methods.dbscan import Dbscan, dbscan_labels
from flic_cli.methods.flic import Flic, flic_labels
from flic_cli.registry import METHODS, load_all

#: Method classes by kind (from :data:`flic_cli.registry.METHODS`).
KINDS: dict[str, type] = load_all(METHODS)

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
]
