"""The extension points of flic, by name: dataset formats, method kinds and ground removers.

This is the one place where each is named. Entries refer to their class as ``"module:Class"``, so
that the command line can list them in its help and check option values without importing numpy or
numba; :func:`load` imports a class when it is needed. To add a dataset format, a method or a ground
remover: write the class (see :class:`flic_cli.io.base.Dataset`,
:class:`flic_cli.methods.base.Method`, :class:`flic_cli.ground.base.GroundRemover`) and add one
line below.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass


@dataclass(frozen=True)
class Entry:
    """A registered class: where it lives and what it is, in a few words for help texts.

    Attributes
    ----------
    target : ``"package.module:Class"``.
    summary : one line for ``--help``.
    labelled : (dataset formats) whether the format carries ground-truth labels.
    """

    target: str
    summary: str
    labelled: bool = False


#: Dataset formats; :func:`flic_cli.io.open_dataset` tries them in this order.
FORMATS: dict[str, Entry] = {
    "semantickitti": Entry(
        "flic_cli.io.semantickitti:SemanticKittiDataset",
        "a SemanticKITTI root (sequences/NN/velodyne/NNNNNN.bin + labels/NNNNNN.label) or one "
        "sequence folder",
        labelled=True,
    ),
    "moosmann": Entry(
        "flic_cli.io.moosmann:MoosmannDataset",
        "a Moosmann log (img.cfg + scanNNNNN.png 16-bit range images) or a folder of logs",
    ),
    "ouster": Entry(
        "flic_cli.io.ouster:OusterPcapDataset",
        "an Ouster pcap with its metadata JSON beside it, or a folder of them",
    ),
    "velodyne": Entry(
        "flic_cli.io.velodyne:VelodynePcapDataset",
        "a Velodyne pcap (VLP-16, VLP-32C, HDL-32E, HDL-64E, ...), or a folder of them",
    ),
    "pcd": Entry(
        "flic_cli.io.pcd:PcdDataset",
        "a PCD file (ASCII, binary, binary_compressed; rows from ring/channel), or a folder",
    ),
    "nuscenes": Entry(
        "flic_cli.io.nuscenes:NuScenesDataset",
        "a nuScenes LIDAR_TOP .pcd.bin, a folder of them or a nuScenes root (Panoptic "
        "nuScenes .npz labels beside them are scored)",
        labelled=True,
    ),
    "bag": Entry(
        "flic_cli.io.bag:BagDataset",
        "a ROS 1 .bag, ROS 2 bag (folder or .db3, .mcap) or MCAP file: PointCloud2, "
        "VelodyneScan or Ouster packets",
    ),
}

#: Method kinds (the ``kind`` of a ``[methods.NAME]`` config table).
METHODS: dict[str, Entry] = {
    "flic": Entry("flic_cli.methods.flic:Flic", "FLIC, with Map Connections"),
    "bogoslavskyi": Entry(
        "flic_cli.methods.bogoslavskyi:Bogoslavskyi", "Bogoslavskyi & Stachniss' angle criterion"
    ),
    "dbscan": Entry("flic_cli.methods.dbscan:Dbscan", "DBSCAN on the 3D points"),
    "bridge": Entry(
        "flic_cli.methods.bridge:Bridge",
        "flic's hole-bridging clusterer: links to the nearest linkable measurement",
    ),
}

#: Ground removers (``[ground.NAME]`` tables, ``--ground-remover NAME``).
REMOVERS: dict[str, Entry] = {
    "paper": Entry("flic_cli.ground.paper:PaperGround", "the FLIC paper's extraction"),
    "bogoslavskyi": Entry(
        "flic_cli.ground.bogoslavskyi:BogoslavskyiGround", "Bogoslavskyi & Stachniss' remover"
    ),
    "column": Entry(
        "flic_cli.ground.column:ColumnGround",
        "flic's own: follows the ground up each column with a local height model",
    ),
    "patchworkpp": Entry(
        "flic_cli.ground.patchworkpp:PatchworkppGround",
        "Patchwork++ on the points (pip install 'flic[patchworkpp]')",
    ),
}


def load(entry: Entry) -> type:
    """The class an entry refers to (imported on first use)."""
    module, _, name = entry.target.partition(":")
    return getattr(importlib.import_module(module), name)


def load_all(entries: dict[str, Entry]) -> dict[str, type]:
    """Every class of a registry, by name."""
    return {name: load(entry) for name, entry in entries.items()}


def choices(entries: dict[str, Entry], labelled_only: bool = False) -> str:
    """```name`: summary; ...`` for help texts."""
    return "; ".join(
        f"`{name}`: {e.summary}" for name, e in entries.items() if e.labelled or not labelled_only
    )
