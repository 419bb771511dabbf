"""Write the sample: the synthetic street as a SemanticKITTI sequence and a Moosmann-style log.

With another sensor profile (``flic sample --sensor vlp16`` ..., :data:`~flic_cli.sample.sensor.
SENSOR_PROFILES`) the sample is the SemanticKITTI sequence alone, cast with that sensor's beam
table and columns, and beside it ``sensor.toml``: the ``[projection]`` table (rows = the sensor's
beams, width = its columns, ring recovery) with which ``flic ... --config OUT/sensor.toml`` reads
the sequence. (The Moosmann format is the HDL-64E log of one recording car; it is written for the
default profile only.)

Every file goes through the writers of :mod:`flic_cli.io`. A sample is written into a temporary
folder beside its target and renamed into place once complete, so that a failure (bad target, full
disk, Ctrl-C) leaves either the previous content of the target or the new sample, never a mix or a
partial dataset.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flic_cli.errors import FlicInputError
from flic_cli.io import (
    ImgCfg,
    atomic_write_bytes,
    write_bin,
    write_calib,
    write_img_cfg,
    write_label,
    write_png_range,
    write_poses,
    write_times,
)
from flic_cli.sample.render import render_kitti
from flic_cli.sample.sensor import (
    DEFAULT_SENSOR,
    EGO_VEHICLE,
    HDL64_PITCH_DEG,
    MOOSMANN_HEIGHT,
    MOOSMANN_WIDTH,
    SENSOR_PROFILES,
    SensorProfile,
    cast,
    moosmann_azimuths,
)
from flic_cli.sample.street import FPS, make_scene
from flic_cli.sensor_params import (
    BRIDGE_GAPS_PER_GAMMA,
    BRIDGE_SWITCH_M,
    bridge_parameters,
    street_beam_gap_deg,
)

__all__ = ["SamplePaths", "default_sample_dir", "ensure_sample", "write_sample"]

#: The comment line of the sample's ``img.cfg``; it also tells a folder holding a sample.
IMG_CFG_COMMENT = (
    "synthetic HDL-64E street (flic sample): imgHSize; imgVSize; horizStartAngle; "
    "horizStopAngle; vertAngle_1..64 (deg, positive = down)"
)

#: KITTI's calibration of sequence 00 (camera projections P0..P3) with Tr = identity: the scans
#: are in the velodyne frame, which the poses use too.
_CALIB: dict[str, np.ndarray] = {
    "P0": np.array(
        [[718.856, 0.0, 607.1928, 0.0], [0.0, 718.856, 185.2157, 0.0], [0.0, 0.0, 1.0, 0.0]]
    ),
    "P1": np.array(
        [[718.856, 0.0, 607.1928, -386.1448], [0.0, 718.856, 185.2157, 0.0], [0.0, 0.0, 1.0, 0.0]]
    ),
    "P2": np.array(
        [
            [718.856, 0.0, 607.1928, 45.38225],
            [0.0, 718.856, 185.2157, -0.1130887],
            [0.0, 0.0, 1.0, 0.003779761],
        ]
    ),
    "P3": np.array(
        [
            [718.856, 0.0, 607.1928, -337.2877],
            [0.0, 718.856, 185.2157, 2.369057],
            [0.0, 0.0, 1.0, 0.004915215],
        ]
    ),
    "Tr": np.eye(3, 4),
}

#: The files of a sample (relative paths), and the top-level entries of a folder holding one
#: (``.complete``: the marker of :func:`ensure_sample`).
_SAMPLE_FILE = re.compile(
    r"semantickitti/sequences/00/(velodyne/\d{6}\.bin|labels/\d{6}\.label"
    r"|calib\.txt|poses\.txt|times\.txt)|moosmann/(img\.cfg|scan\d{5}\.png)|\.complete"
    r"|sensor\.toml"
)
_SAMPLE_TOP = frozenset({"semantickitti", "moosmann", ".complete", "sensor.toml"})

#: The first line of a profile sample's ``sensor.toml`` starts with this (it tells a sample too).
SENSOR_TOML_MARK = "# flic sample --sensor "


@dataclass
class SamplePaths:
    """Where a written sample lies.

    Attributes
    ----------
    kitti_root : the SemanticKITTI root (``<out>/semantickitti``, holding ``sequences/00``).
    moosmann_log : the Moosmann-style log folder (``<out>/moosmann``); None for a sensor profile
        other than the default (no Moosmann log is written).
    seed, frames, kitti_width : the parameters it was written with.
    sensor : the sensor profile's name (:data:`~flic_cli.sample.sensor.SENSOR_PROFILES`).
    config : ``<out>/sensor.toml``, the ``--config`` file that reads the sequence (its
        ``[projection]`` table); None for the default profile, which the default projection reads.
    """

    kitti_root: Path
    moosmann_log: Path | None
    seed: int = 0
    frames: int = 20
    kitti_width: int = 2048
    sensor: str = DEFAULT_SENSOR
    config: Path | None = None
    _truth: dict[int, tuple[np.ndarray, np.ndarray]] = field(
        default_factory=dict, repr=False, compare=False
    )

    @property
    def kitti_sequence(self) -> Path:
        """The sequence folder ``<kitti_root>/sequences/00``."""
        return self.kitti_root / "sequences" / "00"

    def moosmann_truth(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Ground truth of a Moosmann frame, which the format itself cannot hold.

        Returns
        -------
        semantic, instance : (64, 870) uint16 arrays, per pixel (0 where there is no return).
        """
        if self.moosmann_log is None:
            raise ValueError(f"a {self.sensor} sample has no Moosmann log")
        if frame not in self._truth:
            _, sem, inst = _moosmann_frame(self.seed, frame)
            self._truth[frame] = (sem, inst)
        return self._truth[frame]


# ---------------------------------------------------------------------------------------------
# The frames
# ---------------------------------------------------------------------------------------------


def _moosmann_frame(seed: int, frame: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ranges, semantic, instance) of a Moosmann frame, 64 x 870, seen past the recording car."""
    rng = np.random.default_rng([seed, frame, 2])
    scene = make_scene(seed, frame)
    return cast(scene, HDL64_PITCH_DEG, moosmann_azimuths(), rng, EGO_VEHICLE)


def _kitti_frame(
    seed: int, frame: int, width: int, pitch_deg: np.ndarray = HDL64_PITCH_DEG
) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, 4) float32 in scan order and labels (N,) uint32 of a KITTI frame."""
    rng = np.random.default_rng([seed, frame, 1])
    scene = make_scene(seed, frame)
    return render_kitti(scene, width=width, pitch_deg=pitch_deg, noise=True, rng=rng)


def sensor_toml(profile: SensorProfile, width: int | None = None) -> str:
    """The ``sensor.toml`` of a profile sample: its ``[projection]`` table, and in comments the
    sensor, where its beam table comes from, and the beam elevations (degrees, top first).

    Parameters
    ----------
    profile : the sensor.
    width : the columns written (default: the profile's).
    """
    width = profile.width if width is None else int(width)
    elev = ", ".join(f"{-p:.3f}" for p in profile.pitch_deg)
    lo, hi = profile.vertical_fov_deg
    text = (
        f"{SENSOR_TOML_MARK}{profile.name}: synthetic {profile.title} street, "
        f"{profile.beams} beams x {width} columns, elevation {lo:+.2f} .. {hi:+.2f} deg\n"
        f"# beam table: {profile.source}\n"
        f"# beam elevations, degrees, top beam first (= image row 0 first): {elev}\n"
        "# Read the sequence beside this file with it, e.g.\n"
        "#   flic evaluate OUT/semantickitti --config OUT/sensor.toml\n"
        "[projection]\n"
        'mode = "rings"\n'
        f"rows = {profile.beams}\n"
        f"width = {width}\n"
    )
    elevation = -np.radians(profile.pitch_deg)
    bridge = bridge_parameters(elevation)
    if bridge:
        gap = street_beam_gap_deg(elevation)
        text += (
            "\n# flic derives the parameters that follow the beam table when it reads the data\n"
            "# (flic_cli.sensor_params; set them in a [methods.NAME] table here to override).\n"
            f"# Here: Bridge's gamma = max(2 deg, {BRIDGE_GAPS_PER_GAMMA:g} x {gap:.3f} deg), "
            f"threshold = max(0.35 m, {BRIDGE_SWITCH_M:g} m x sin(gamma)):\n"
            "# " + ", ".join(f"{k} = {v!r}" for k, v in bridge.items()) + "\n"
        )
    return text


def _write_files(
    folder: Path, frames: int, seed: int, kitti_width: int, sensor: str = DEFAULT_SENSOR
) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Write the sample's files into ``folder``; the Moosmann ground truth of every frame (none
    for a profile other than the default)."""
    seq = folder / "semantickitti" / "sequences" / "00"
    moos = folder / "moosmann"
    default = sensor == DEFAULT_SENSOR
    profile = SENSOR_PROFILES[sensor]
    truth: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    poses = []
    for k in range(frames):
        pts, labels = _kitti_frame(seed, k, kitti_width, profile.pitch_deg)
        write_bin(seq / "velodyne" / f"{k:06d}.bin", pts)
        write_label(seq / "labels" / f"{k:06d}.label", labels)
        if default:
            ranges, sem, inst = _moosmann_frame(seed, k)
            write_png_range(moos / f"scan{k:05d}.png", ranges)
            truth[k] = (sem, inst)
        poses.append(make_scene(seed, k).pose)
    write_calib(seq / "calib.txt", _CALIB, float_format=".6e")
    write_poses(seq / "poses.txt", np.stack(poses), float_format=".6e")
    write_times(seq / "times.txt", np.arange(frames) / FPS)
    if not default:
        atomic_write_bytes(folder / "sensor.toml", sensor_toml(profile, kitti_width).encode())
        return truth
    # The horizontal angles are integers so that the file reads "180; -180" as the real ones do.
    cfg = ImgCfg(MOOSMANN_WIDTH, MOOSMANN_HEIGHT, 180, -180, HDL64_PITCH_DEG)
    write_img_cfg(moos / "img.cfg", cfg, comment=IMG_CFG_COMMENT, pitch_format=".4f")
    return truth


# ---------------------------------------------------------------------------------------------
# Checks and the temporary folder
# ---------------------------------------------------------------------------------------------


def _check_sensor(sensor: str) -> SensorProfile:
    """The profile named ``sensor``; a one-line error naming the known ones otherwise."""
    if sensor not in SENSOR_PROFILES:
        raise FlicInputError(
            None, f"--sensor {sensor}: unknown sensor; one of {', '.join(SENSOR_PROFILES)}"
        )
    return SENSOR_PROFILES[sensor]


def _check_parameters(frames: int, seed: int, kitti_width: int) -> None:
    """One-line errors for parameters the generator cannot take."""
    if int(frames) != frames or frames < 1:
        raise FlicInputError(None, f"--frames {frames}: the number of frames must be at least 1")
    if int(seed) != seed or seed < 0:
        raise FlicInputError(None, f"--seed {seed}: the seed must be an integer >= 0")
    if int(kitti_width) != kitti_width or kitti_width < 1:
        raise FlicInputError(None, f"kitti_width {kitti_width}: must be an integer >= 1")


def _is_sample(folder: Path) -> bool:
    """True when ``folder`` holds a flic sample and nothing else (so it may be replaced)."""
    try:
        top = {p.name for p in folder.iterdir()}
        if not top <= _SAMPLE_TOP:
            return False
        cfg = folder / "moosmann" / "img.cfg"
        toml = folder / "sensor.toml"
        if cfg.is_file():
            if not cfg.read_text(errors="replace").startswith(f"# {IMG_CFG_COMMENT}\n"):
                return False
        elif not toml.is_file() or not toml.read_text(errors="replace").startswith(
            SENSOR_TOML_MARK
        ):
            return False
        return all(
            _SAMPLE_FILE.fullmatch(p.relative_to(folder).as_posix())
            for p in folder.rglob("*")
            if not p.is_dir() or p.is_symlink()
        )
    except OSError:
        return False


def _check_out(out: Path) -> None:
    """Refuse a target that is a file, or a folder with content other than a flic sample."""
    if out.exists() and not out.is_dir():
        raise FlicInputError(out, "is a file, expected a folder (new, empty, or holding a sample)")
    if out.is_dir():
        try:
            empty = next(out.iterdir(), None) is None
        except OSError as exc:
            raise FlicInputError(out, f"cannot be read ({exc.strerror})") from None
        if not empty and not _is_sample(out):
            raise FlicInputError(
                out,
                "is a folder that holds other files than a flic sample; "
                "choose a new or empty folder",
            )


def _temp_beside(out: Path) -> tuple[Path, Path | None]:
    """Create the temporary folder beside ``out`` (and missing parent folders).

    Returns
    -------
    tmp : the temporary folder.
    created : the outermost parent folder that was created (to remove on failure), or None.
    """
    parent = out.parent
    created = None
    missing = [p for p in (parent, *parent.parents) if not p.exists()]
    if missing:
        created = missing[-1]
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):
        raise FlicInputError(out, "cannot be created: a parent is a file, not a folder") from None
    except OSError as exc:
        raise FlicInputError(out, f"cannot be created ({exc.strerror})") from None
    try:
        tmp = _fresh_dir(parent, f".{out.name}.tmp-")
    except PermissionError:
        _remove(created)
        raise FlicInputError(
            out, f"cannot be written: its folder {parent} is not writable"
        ) from None
    except OSError as exc:
        _remove(created)
        raise FlicInputError(
            out, f"cannot be written: no folder can be made in {parent} ({exc.strerror})"
        ) from None
    return tmp, created


def _fresh_dir(parent: Path, prefix: str) -> Path:
    """A new folder ``<parent>/<prefix><pid>-<random>``, with the permissions the umask gives
    (unlike :func:`tempfile.mkdtemp`'s 0700: the sample is renamed into place as it is)."""
    while True:
        path = parent / f"{prefix}{os.getpid()}-{secrets.token_hex(4)}"
        try:
            path.mkdir()
        except FileExistsError:
            continue
        return path


def _remove(path: Path | None) -> None:
    if path is not None:
        shutil.rmtree(path, ignore_errors=True)


def _commit(tmp: Path, out: Path) -> None:
    """Rename the complete sample ``tmp`` to ``out`` (absent, empty, or a previous sample)."""
    old = None
    if out.is_dir() and next(out.iterdir(), None) is not None:
        old = _fresh_dir(out.parent, f".{out.name}.old-")
        os.replace(out, old)  # a rename replaces an empty folder (old, and out when empty)
    try:
        os.replace(tmp, out)
    except OSError:
        if old is not None:
            os.replace(old, out)
        raise
    _remove(old)


def _write_atomically(
    out: Path,
    frames: int,
    seed: int,
    kitti_width: int,
    stamp: str | None = None,
    sensor: str = DEFAULT_SENSOR,
) -> tuple[Path, Path | None, dict[int, tuple[np.ndarray, np.ndarray]]]:
    """Write the sample into a temporary folder beside ``out``; nothing is left on failure.

    Returns the temporary folder, the parent folder created for it (or None) and the Moosmann
    ground truth. ``stamp``: content of a ``.complete`` marker to write last (None: none).
    """
    tmp, created = _temp_beside(out)
    try:
        truth = _write_files(tmp, frames, seed, kitti_width, sensor)
        if stamp is not None:
            atomic_write_bytes(tmp / ".complete", stamp.encode())
    except OSError as exc:
        _remove(tmp)
        _remove(created)
        raise FlicInputError(out, f"writing the sample failed ({exc.strerror})") from None
    except BaseException:
        _remove(tmp)
        _remove(created)
        raise
    return tmp, created, truth


# ---------------------------------------------------------------------------------------------
# Public
# ---------------------------------------------------------------------------------------------


def write_sample(
    out: str | Path,
    frames: int = 20,
    seed: int = 0,
    kitti_width: int | None = None,
    sensor: str = DEFAULT_SENSOR,
) -> SamplePaths:
    """Write the synthetic street as a SemanticKITTI sequence and as a Moosmann-style log.

    With ``sensor`` other than ``"hdl64e"`` the street is cast with that sensor's beams and
    columns (:data:`~flic_cli.sample.sensor.SENSOR_PROFILES`), as the SemanticKITTI sequence and
    ``out/sensor.toml`` (the ``[projection]`` table to read it with, see :func:`sensor_toml`); no
    Moosmann log is written then.

    Layout::

        out/semantickitti/sequences/00/velodyne/000000.bin   float32 x, y, z, remission
        out/semantickitti/sequences/00/labels/000000.label   uint32 semantic | instance << 16
        out/semantickitti/sequences/00/{calib,poses,times}.txt
        out/moosmann/img.cfg
        out/moosmann/scan00000.png                            16-bit, range_m * 500, 0 = none

    The sample is written into a temporary folder beside ``out`` and renamed to ``out`` once
    complete: on any failure ``out`` is left as it was and no temporary folder remains.

    Parameters
    ----------
    out : output folder: new (created, with missing parents), empty, or holding a sample written
        before (which is replaced).
    frames : number of frames (10 Hz), at least 1.
    seed : street seed, an integer >= 0.
    kitti_width : rays per ring of the KITTI scans (azimuth resolution 360 deg / width);
        default: the sensor's columns (2048 for the HDL-64E).
    sensor : the sensor profile's name (``vlp16``, ``vlp32c``, ``hdl32e``, ``hdl64e``,
        ``os1-64``, ``os1-128``, ``os2-128``).

    Returns
    -------
    SamplePaths
        The dataset roots; the Moosmann ground truth of the written frames is kept in memory
        (:meth:`SamplePaths.moosmann_truth`), since the format has no labels.

    Raises
    ------
    FlicInputError
        Before writing anything: ``frames`` < 1, ``seed`` < 0, an unknown ``sensor``, ``out`` is
        a file or a folder with
        other content than a sample, or ``out``'s folder cannot be created or written to. While
        writing: when a write fails (e.g. a full disk); nothing is left behind.
    """
    out = Path(out)
    profile = _check_sensor(sensor)
    if kitti_width is None:
        kitti_width = profile.width
    _check_parameters(frames, seed, kitti_width)
    # A link to a folder: the sample goes into the folder, the link stays.
    real = out.resolve() if out.is_symlink() else out
    _check_out(real)
    tmp, created, truth = _write_atomically(real, frames, seed, kitti_width, sensor=sensor)
    try:
        _commit(tmp, real)
    except OSError as exc:
        _remove(tmp)
        _remove(created)
        raise FlicInputError(out, f"cannot be replaced ({exc.strerror})") from None
    default = sensor == DEFAULT_SENSOR
    paths = SamplePaths(
        out / "semantickitti",
        out / "moosmann" if default else None,
        seed,
        frames,
        kitti_width,
        sensor,
        None if default else out / "sensor.toml",
    )
    paths._truth.update(truth)
    return paths


def default_sample_dir() -> Path:
    """Per-user cache folder of the embedded sample: ``$FLIC_SAMPLE_DIR`` or
    ``~/.cache/flic/sample-v2`` (the version changes whenever the generated content does)."""
    env = os.environ.get("FLIC_SAMPLE_DIR")
    if env:
        return Path(env).expanduser()
    return Path.home() / ".cache" / "flic" / "sample-v2"


def ensure_sample(frames: int = 20, seed: int = 0) -> SamplePaths:
    """The default sample in :func:`default_sample_dir`, written on first use.

    The sample is written as by :func:`write_sample` (a temporary folder renamed into place), with
    a ``.complete`` marker recording its parameters; a killed run leaves no half-written sample.
    A sample written with other parameters is replaced; when another process puts the same sample
    in place first, its copy is used.

    Parameters
    ----------
    frames : number of frames.
    seed : street seed.

    Returns
    -------
    SamplePaths

    Raises
    ------
    FlicInputError
        As :func:`write_sample` (e.g. ``$FLIC_SAMPLE_DIR`` is a file or a folder with other
        content).
    """
    target = default_sample_dir()
    target = target.resolve() if target.is_symlink() else target
    stamp = f"seed={seed} frames={frames} kitti_width=2048\n"
    marker = target / ".complete"

    def done() -> bool:
        try:
            return marker.is_file() and marker.read_text() == stamp
        except OSError:
            return False

    paths = SamplePaths(target / "semantickitti", target / "moosmann", seed, frames, 2048)
    if done():
        return paths
    _check_parameters(frames, seed, 2048)
    _check_out(target)
    tmp, _, truth = _write_atomically(target, frames, seed, 2048, stamp)
    try:
        if not done():  # else: written meanwhile by another process
            _commit(tmp, target)
    except OSError as exc:
        if not done():  # another process renamed its copy into place first
            raise FlicInputError(target, f"cannot be replaced ({exc.strerror})") from None
    finally:
        _remove(tmp)
    paths._truth.update(truth)
    return paths
