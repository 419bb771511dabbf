"""nuScenes LIDAR_TOP sweeps (``.pcd.bin``: float32 x, y, z, intensity, ring), one frame per
file, with Panoptic nuScenes labels where they exist.

DATA is a ``.pcd.bin`` file, a folder of them, or a nuScenes root (its
``samples/LIDAR_TOP/``). Rows from the ring field (HDL-32E, ring 0 = lowest beam); columns: the
firing when the file is stored firing by firing (the ring cycles 0..H-1, as nuScenes writes
LIDAR_TOP), otherwise the azimuth. Points within 1 m of the sensor are left out (label 0), as the
nuScenes devkit drops them: in LIDAR_TOP they are the no-return and ego-vehicle points.

Labels: a Panoptic nuScenes ``.npz`` (array ``data``, one uint16 per point = category x 1000 +
instance), found as ``<name>_panoptic.npz`` or ``<name>.npz`` beside the sweep (``<name>`` = the
file name without ``.pcd.bin``), or, in a nuScenes root, through ``v1.0-*/sample_data.json`` as
``panoptic/v1.0-*/<token>_panoptic.npz``. The 32 nuScenes categories are mapped to SemanticKITTI
classes (:data:`CATEGORY_TO_KITTI`), so that ``flic evaluate`` scores them with the same protocol:
the nuScenes thing classes car, truck, bus, trailer, construction vehicle, bicycle, motorcycle
and pedestrian are things there; barrier and traffic cone, nuScenes things that SemanticKITTI's
table has no thing class for, are mapped to fence and traffic-sign (scored as stuff).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flic_cli.classes import THING_LUT
from flic_cli.errors import FlicInputError
from flic_cli.io.base import Frame, FrameRef
from flic_cli.io.pcd import cloud_geometry, kept_points
from flic_cli.io.rings import ring_image
from flic_cli.io.sensor import FileInfo, SensorFileDataset, SensorModel
from flic_cli.labels import encode

FORMAT = "nuscenes"
SUFFIX = ".pcd.bin"
POINT_BYTES = 20
MIN_RANGE_M = 1.0
"""Points nearer than this are left out (the nuScenes devkit's ``remove_close`` radius)."""
BEAMS = 32  # HDL-32E

#: nuScenes lidarseg category index -> SemanticKITTI raw class (0 = unlabeled, ignored).
CATEGORY_TO_KITTI: dict[int, int] = {
    0: 0,  # noise
    1: 0,  # animal
    2: 30, 3: 30, 4: 30, 6: 30,  # pedestrian adult, child, construction worker, police officer
    5: 0, 7: 0, 8: 0,  # personal mobility, stroller, wheelchair (ignored by the challenge)
    9: 51,  # movable_object.barrier -> fence (SemanticKITTI has no barrier thing)
    10: 0, 11: 0, 13: 0,  # debris, pushable_pullable, bicycle_rack
    12: 81,  # movable_object.trafficcone -> traffic-sign (no traffic-cone thing)
    14: 11,  # vehicle.bicycle
    15: 13, 16: 13,  # bus bendy, rigid
    17: 10,  # vehicle.car
    18: 20,  # vehicle.construction -> other-vehicle
    19: 0, 20: 0,  # ambulance, police (ignored by the challenge)
    21: 15,  # vehicle.motorcycle
    22: 20,  # vehicle.trailer -> other-vehicle
    23: 18,  # vehicle.truck
    24: 40,  # flat.driveable_surface -> road
    25: 49,  # flat.other -> other-ground
    26: 48,  # flat.sidewalk
    27: 72,  # flat.terrain
    28: 50,  # static.manmade -> building
    29: 0,  # static.other
    30: 70,  # static.vegetation
    31: 0,  # vehicle.ego
}  # fmt: skip


def read_pcd_bin(path: str | Path) -> np.ndarray:
    """(N, 5) float32 x, y, z, intensity, ring of a LIDAR_TOP ``.pcd.bin``.

    Raises
    ------
    FlicInputError
        When the file cannot be read or its size is not a multiple of 20 bytes.
    """
    from flic_cli.io.atomic import read_bytes

    data = read_bytes(path)
    if len(data) % POINT_BYTES:
        raise FlicInputError(
            path,
            f"is {len(data):,} bytes, not a multiple of {POINT_BYTES} (5 float32 per point: "
            "x, y, z, intensity, ring): not a nuScenes LIDAR_TOP .pcd.bin, or truncated",
        )
    return np.frombuffer(data, dtype="<f4").reshape(-1, 5)


def read_panoptic(path: str | Path, n_points: int) -> np.ndarray:
    """(N,) uint32 SemanticKITTI-encoded labels of a Panoptic nuScenes ``.npz``.

    The semantic class is :data:`CATEGORY_TO_KITTI` of ``data // 1000``, the instance id
    ``data % 1000`` for SemanticKITTI thing classes, 0 for the others.

    Raises
    ------
    FlicInputError
        When the file has no ``data`` array or not one value per point.
    """
    try:
        with np.load(path) as npz:
            if "data" not in npz:
                raise FlicInputError(path, f"has no 'data' array (has: {', '.join(npz.files)})")
            data = np.asarray(npz["data"]).reshape(-1)
    except (OSError, ValueError) as exc:
        raise FlicInputError(path, f"is not a readable .npz ({exc})") from None
    if data.size != n_points:
        raise FlicInputError(path, f"has {data.size} labels, but its sweep {n_points} points")
    data = data.astype(np.int64)
    lut = np.zeros(max(CATEGORY_TO_KITTI) + 1, dtype=np.int64)
    for cat, cls in CATEGORY_TO_KITTI.items():
        lut[cat] = cls
    cat = data // 1000
    if cat.size and (cat.min() < 0 or cat.max() >= lut.size):
        raise FlicInputError(path, f"has category {int(cat.max())}, beyond nuScenes' 32")
    sem = lut[cat]
    inst = np.where(THING_LUT[sem], data % 1000, 0)  # barrier / traffic cone: stuff here
    return encode(sem.astype(np.uint32), inst.astype(np.uint32))


def _token_labels(root: Path) -> dict[str, Path]:
    """In a nuScenes root: sweep file name -> its ``panoptic/<version>/<token>_panoptic.npz``."""
    out: dict[str, Path] = {}
    for table in sorted(root.glob("v1.0-*/sample_data.json")):
        version = table.parent.name
        try:
            rows = json.loads(table.read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise FlicInputError(table, f"cannot be read ({exc})") from None
        for row in rows:
            fn = str(row.get("filename", ""))
            if fn.endswith(SUFFIX):
                npz = root / "panoptic" / version / f"{row['token']}_panoptic.npz"
                if npz.is_file():
                    out[Path(fn).name] = npz
    return out


@dataclass
class _BinState:
    keep: np.ndarray | None
    ring: np.ndarray
    column: np.ndarray
    width: int
    elevation: np.ndarray


class NuScenesDataset(SensorFileDataset):
    """nuScenes LIDAR_TOP ``.pcd.bin`` sweeps (implements :class:`flic_cli.io.base.Dataset`)."""

    format = FORMAT
    suffixes = (SUFFIX,)

    @classmethod
    def _files(cls, root: Path) -> list[Path]:
        if root.is_dir() and (root / "samples" / "LIDAR_TOP").is_dir():
            root = root / "samples" / "LIDAR_TOP"
        return super()._files(root)

    def __init__(
        self,
        root: str | Path,
        sequences: list[str] | None = None,
        frames: tuple[int | None, int | None] | None = None,
        require_labels: bool = False,
        **options: int | None,
    ) -> None:
        root = Path(root)
        self._tokens = _token_labels(root) if root.is_dir() else {}
        super().__init__(root, sequences, frames, require_labels, **options)

    def _label_path(self, path: Path) -> Path | None:
        name = path.name[: -len(SUFFIX)]
        for cand in (path.with_name(f"{name}_panoptic.npz"), path.with_name(f"{name}.npz")):
            if cand.is_file():
                return cand
        return self._tokens.get(path.name)

    def _open(self, path: Path) -> FileInfo:
        pts = read_pcd_bin(path)
        xyz = np.ascontiguousarray(pts[:, :3])
        keep = kept_points(xyz, MIN_RANGE_M)
        ring_all = pts[:, 4]
        if not np.all((ring_all >= 0) & (ring_all < 256) & (ring_all == np.round(ring_all))):
            raise FlicInputError(path, "has ring values that are not beam numbers 0..255")
        ring_all = ring_all.astype(np.int64)
        n = pts.shape[0]
        h = max(BEAMS, int(ring_all.max()) + 1) if n else BEAMS
        notes = [f"points within {MIN_RANGE_M:g} m left out: {n - int(keep.sum()):,}"]
        firing_major = n % h == 0 and np.array_equal(ring_all, np.arange(n) % h)
        geo = cloud_geometry(xyz[keep], ring_all[keep], None, "nuScenes LIDAR_TOP", str(path), h)
        if firing_major:  # column = firing, rolled so that column 0 looks backwards
            width = n // h
            firing = np.arange(n) // h
            az0 = float(np.arctan2(xyz[keep][:, 1][:50].mean(), xyz[keep][:, 0][:50].mean()))
            first = int(firing[keep][0]) if keep.any() else 0
            shift = int(np.floor((np.pi - az0) / (2 * np.pi) * width)) - first
            column = (firing[keep] + shift) % width
            notes.append(f"columns: the {width:,} firings, stored firing by firing")
        else:
            width, column = geo.width, geo.column
            notes.append("columns from the points' azimuth")
        model = SensorModel(
            name="Velodyne HDL-32E (nuScenes LIDAR_TOP)",
            elevation=geo.elevation,
            azimuth_offset=np.zeros(geo.elevation.size),
            columns=width,
            angles_from="fields",
            columns_from="firings in the sweep" if firing_major else "estimated azimuth step",
            notes=tuple(notes) + tuple(n for n in geo.model.notes if "columns" not in n),
        )
        label = self._label_path(path)
        state = _BinState(None if keep.all() else keep, geo.ring, column, width, geo.elevation)
        return FileInfo(path, 1, model, np.array([int(keep.sum())]), [], state, [label])

    def _load(self, info: FileInfo, k: int) -> Frame:
        state: _BinState = info.state  # type: ignore[assignment]
        pts = read_pcd_bin(info.path)
        xyz = pts[:, :3]
        if state.keep is not None:
            if state.keep.size != xyz.shape[0]:
                raise FlicInputError(info.path, "changed since it was opened")
            xyz = xyz[state.keep]
        xyz = np.ascontiguousarray(xyz)
        image = ring_image(xyz, state.ring, state.column, state.width, state.elevation)
        label_path = info.label_paths[k] if info.label_paths else None
        labels = None
        if label_path is not None:
            labels = read_panoptic(label_path, pts.shape[0])
            if state.keep is not None:
                labels = labels[state.keep]
        ref = FrameRef(self.sequence_name(info.path), k, info.path, label_path, FORMAT, index=k)
        return Frame(ref, xyz, labels, image, finite=state.keep)
