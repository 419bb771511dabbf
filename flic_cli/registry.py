"""The extension points of flic, by name: dataset formats, method kinds and ground removers.

This is the one place where each is named. Entries refer to their class as ``"module:Class"``, so
that the command line can list them in its help and check option values without importing numpy or
numba; :func:`load` imports a class when it is needed (and nothing imports a format module before
then, so a format whose optional package is missing breaks nothing until it is used). To add a
dataset format, a method or a ground remover: write the class (see
:class:`flic_cli.io.base.Dataset`, :class:`flic_cli.methods.base.Method`,
:class:`flic_cli.ground.base.GroundRemover`) and add one line below -- or, from outside flic (a
plugin, a test), call :func:`register`.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from dataclasses import dataclass
from typing import Literal

from flic_cli.errors import FlicInputError


@dataclass(frozen=True)
class Entry:
    """A registered class: where it lives and what the runs need to know before loading it.

    Attributes
    ----------
    target : ``"package.module:Class"``.
    summary : one line for ``--help``.
    labelled : (dataset formats) whether the format can carry ground-truth labels (the help of
        ``flic evaluate`` and ``sweep-threshold`` lists only such formats; the runs check each
        frame's labels through :meth:`flic_cli.io.base.Dataset.load`).
    frames_per_file : (dataset formats) ``"one"`` (a file per frame: SemanticKITTI ``.bin``,
        Moosmann ``.png``) or ``"many"`` (one file holds many frames, as a pcap or a bag: its
        :class:`flic_cli.io.base.FrameRef` carry the frame's ``index`` in the file).
    requires : the import name of an optional package the class needs (None: none); checked by
        :func:`check_installed` before the class is loaded.
    install : how to install it, for the error message (``"pip install 'flic[ouster]'"``).
    exports : (dataset formats) the ``flic segment --export`` kinds only this format's input can
        take (``"mcap"``, ``"bag"``: messages that keep the input's stamps and frame id).
    beam_angles : (dataset formats) where the beam angles of an image come from when the format
        gives no sensor model (``flic info``), e.g. ``"metadata (img.cfg)"``; None: estimated.
    """

    target: str
    summary: str
    labelled: bool = False
    frames_per_file: Literal["one", "many"] = "one"
    requires: str | None = None
    install: str | None = None
    exports: tuple[str, ...] = ()
    beam_angles: str | None = None

    def missing(self) -> str | None:
        """None when the class can be used; else the one-line reason (package and install hint)."""
        if self.requires is None or importlib.util.find_spec(self.requires) is not None:
            return None
        hint = f" ({self.install})" if self.install else ""
        return f"needs the optional package {self.requires!r}, which is not installed{hint}"


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
        beam_angles="metadata (img.cfg)",
    ),
    "ouster": Entry(
        "flic_cli.io.ouster:OusterPcapDataset",
        "an Ouster pcap with its metadata JSON beside it, or a folder of them",
        frames_per_file="many",
    ),
    "velodyne": Entry(
        "flic_cli.io.velodyne:VelodynePcapDataset",
        "a Velodyne pcap (VLP-16, VLP-32C, HDL-32E, HDL-64E, ...), or a folder of them",
        frames_per_file="many",
    ),
    "osf": Entry(
        "flic_cli.io.osf:OsfDataset",
        "an Ouster OSF file, or a folder of them (needs ouster-sdk, see docs/sensors.md)",
        frames_per_file="many",
        requires="ouster",
        install="pip install --no-deps ouster-sdk",
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
        frames_per_file="many",
        requires="rosbags",
        install="pip install rosbags",
        exports=("mcap", "bag"),
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
    "euclidean": Entry(
        "flic_cli.methods.euclidean:Euclidean", "PCL's Euclidean cluster extraction (3D points)"
    ),
    "hdbscan": Entry("flic_cli.methods.hdbscan:Hdbscan", "scikit-learn's HDBSCAN (3D points)"),
    "slr": Entry("flic_cli.methods.slr:Slr", "scan-line run, Zermas et al. 2017 (range image)"),
    "cvc": Entry("flic_cli.methods.cvc:Cvc", "curved-voxel clustering, Park et al. 2019"),
    "alpine": Entry(
        "flic_cli.methods.alpine:Alpine",
        "ALPINE, Sautier et al. 2025: per-class bird's-eye kNN graph (needs semantics)",
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
        requires="pypatchworkpp",
        install="pip install 'flic[patchworkpp]'",
    ),
}


#: The registries by the word :func:`register` takes.
TABLES: dict[str, dict[str, Entry]] = {"format": FORMATS, "method": METHODS, "remover": REMOVERS}


def register(
    kind: Literal["format", "method", "remover"], name: str, entry: Entry, replace: bool = False
) -> None:
    """Add a class to a registry from outside this file (a plugin, a test).

    Register before the first use: :mod:`flic_cli.methods` and :mod:`flic_cli.ground` load their
    registries when first imported, and ``flic_cli.methods.KINDS`` / ``flic_cli.ground.REMOVERS``
    are refreshed here when already loaded.

    Parameters
    ----------
    kind : which registry.
    name : the name (a format's name, a method ``kind``, a remover's name).
    entry : where the class lives.
    replace : allow replacing an entry of that name.

    Raises
    ------
    ValueError
        When the name is taken (and ``replace`` is False) or ``entry.target`` is not
        ``"module:Class"``.
    """
    table = TABLES[kind]
    if name in table and not replace:
        raise ValueError(f"{kind} {name!r} is registered already ({table[name].target})")
    module, sep, cls = entry.target.partition(":")
    if not (module and sep and cls):
        raise ValueError(f"target must be 'module:Class', got {entry.target!r}")
    table[name] = entry
    loaded = _loaded(kind)
    if loaded is not None:
        loaded[name] = load(entry)


def unregister(kind: Literal["format", "method", "remover"], name: str) -> None:
    """Remove what :func:`register` added (tests clean up with it)."""
    TABLES[kind].pop(name, None)
    loaded = _loaded(kind)
    if loaded is not None:
        loaded.pop(name, None)


#: Where the classes of a registry are kept once loaded (module, attribute).
_LOADED = {"method": ("flic_cli.methods", "KINDS"), "remover": ("flic_cli.ground", "REMOVERS")}


def _loaded(kind: str) -> dict[str, type] | None:
    """The loaded classes of registry ``kind`` when its package was imported already, else None."""
    if kind not in _LOADED or _LOADED[kind][0] not in sys.modules:
        return None
    return getattr(sys.modules[_LOADED[kind][0]], _LOADED[kind][1])


def check_installed(name: str, entry: Entry) -> None:
    """Fail with the install hint when ``entry`` needs an optional package that is missing.

    Raises
    ------
    FlicInputError
        ``<name> needs the optional package ... (pip install ...)``.
    """
    reason = entry.missing()
    if reason is not None:
        raise FlicInputError(None, f"{name} {reason}")


def load(entry: Entry) -> type:
    """The class an entry refers to (imported on first use; this is the registry's one lazy
    load by name)."""
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
