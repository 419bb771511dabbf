"""Tests of flic_cli.io: readers, writers, datasets, and their one-line errors."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from PIL import Image

from flic_cli.errors import FlicInputError
from flic_cli.io import (
    ImgCfg,
    MoosmannDataset,
    SemanticKittiDataset,
    atomic_write,
    atomic_write_bytes,
    open_dataset,
    parse_frames,
    parse_sequences,
    predictions_path,
    read_bin,
    read_calib,
    read_img_cfg,
    read_label,
    read_png_range,
    read_poses,
    read_predictions,
    read_scan,
    write_bin,
    write_calib,
    write_img_cfg,
    write_label,
    write_png_range,
    write_poses,
    write_predictions,
)
from flic_cli.labels import encode, instance, semantic

RNG = np.random.default_rng(0)
CFG = ImgCfg(16, 4, 180.0, -180.0, np.array([-2.0, 3.5, 9.0, 24.5]))


def leftovers(folder: Path) -> list[str]:
    """Names of temporary files that a write left in ``folder``."""
    return [p.name for p in folder.iterdir() if ".tmp-" in p.name]


def make_kitti(root: Path, sequences=("00", "01"), frames=range(5), labels=True) -> Path:
    """A tiny SemanticKITTI root: 10 points per frame, labels = frame number."""
    for seq in sequences:
        for f in frames:
            write_bin(root / "sequences" / seq / "velodyne" / f"{f:06d}.bin", RNG.random((10, 4)))
            if labels:
                write_label(
                    root / "sequences" / seq / "labels" / f"{f:06d}.label",
                    np.full(10, f, dtype=np.uint32),
                )
    return root


def make_log(folder: Path, frames=(1, 2, 5), cfg_in: str = ".", scans_in: str = ".") -> Path:
    """A tiny Moosmann log: frame f has range f metres in its first row, nothing elsewhere."""
    write_img_cfg(folder / cfg_in / "img.cfg", CFG)
    for f in frames:
        ranges = np.zeros((CFG.height, CFG.width), dtype=np.float32)
        ranges[0] = f
        write_png_range(folder / scans_in / f"scan{f:05d}.png", ranges)
    return folder


# ---------------------------------------------------------------------------------------------
# Atomic writes
# ---------------------------------------------------------------------------------------------


def test_atomic_write_creates_parents_and_replaces(tmp_path: Path) -> None:
    target = tmp_path / "a" / "b" / "x.txt"
    atomic_write_bytes(target, b"one")
    atomic_write_bytes(target, b"two")
    assert target.read_bytes() == b"two"
    assert leftovers(target.parent) == []


def test_atomic_write_failure_keeps_old_file_and_leaves_no_temp(tmp_path: Path) -> None:
    target = tmp_path / "x.txt"
    target.write_bytes(b"old")
    with pytest.raises(RuntimeError), atomic_write(target) as tmp:
        assert tmp.parent == tmp_path and tmp.name.startswith(".x.txt.tmp-")
        tmp.write_bytes(b"half")
        raise RuntimeError("boom")
    assert target.read_bytes() == b"old"
    assert leftovers(tmp_path) == []


def test_unwritable_output_folder(tmp_path: Path) -> None:
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    folder = blocker / "out"
    for write in (
        lambda: atomic_write_bytes(folder / "x.bin", b"x"),
        lambda: write_bin(folder / "x.bin", np.zeros((3, 4))),
        lambda: write_png_range(folder / "scan00000.png", np.zeros((4, 16))),
        lambda: write_predictions(folder, "00", 0, np.zeros(3, dtype=int)),
    ):
        with pytest.raises(FlicInputError, match="output folder is not writable") as err:
            write()
        assert str(blocker) in str(err.value)
    assert blocker.read_text() == "not a folder"
    assert leftovers(tmp_path) == []


def test_failing_png_write_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def broken_save(self, fp, format=None, **kwargs):  # noqa: A002 - Pillow's own signature
        Path(fp).write_bytes(b"\x89PNG half")
        raise OSError("disk full")

    monkeypatch.setattr(Image.Image, "save", broken_save)
    with pytest.raises(OSError, match="disk full"):
        write_png_range(tmp_path / "scan00000.png", np.ones((4, 16)))
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# SemanticKITTI round trips
# ---------------------------------------------------------------------------------------------


@settings(max_examples=25, deadline=None)
@given(
    arrays(
        np.float32,
        st.tuples(st.integers(1, 50), st.just(4)),
        elements=st.floats(-1e4, 1e4, width=32),
    )
)
def test_bin_round_trip(tmp_path_factory: pytest.TempPathFactory, points: np.ndarray) -> None:
    path = tmp_path_factory.mktemp("bin") / "000000.bin"
    write_bin(path, points)
    assert path.stat().st_size == points.shape[0] * 16
    np.testing.assert_array_equal(read_bin(path), points)
    scan = read_scan(path)
    np.testing.assert_array_equal(scan.points, points[:, :3])
    np.testing.assert_array_equal(scan.remission, points[:, 3])
    assert scan.points.dtype == np.float32 and scan.points.flags.writeable
    assert scan.labels is None


def test_bin_with_three_columns_gets_zero_remission(tmp_path: Path) -> None:
    points = RNG.random((7, 3)).astype(np.float32)
    write_bin(tmp_path / "x.bin", points)
    raw = read_bin(tmp_path / "x.bin")
    np.testing.assert_array_equal(raw[:, :3], points)
    assert not raw[:, 3].any()


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 0xFFFF), st.integers(0, 0xFFFF)), min_size=1, max_size=50))
def test_label_round_trip(tmp_path_factory: pytest.TempPathFactory, pairs: list) -> None:
    sem, ins = (np.array(v) for v in zip(*pairs, strict=True))
    labels = encode(sem, ins)
    path = tmp_path_factory.mktemp("label") / "000000.label"
    write_label(path, labels)
    back = read_label(path, len(pairs))
    assert back.dtype == np.uint32
    np.testing.assert_array_equal(back, labels)
    np.testing.assert_array_equal(semantic(back), sem)
    np.testing.assert_array_equal(instance(back), ins)


def test_encode_labels_rejects_ids_beyond_16_bits() -> None:
    with pytest.raises(ValueError, match="instance ids must lie in 0..65535"):
        encode(np.zeros(2), np.array([1, 70000]))


def test_calib_round_trip(tmp_path: Path) -> None:
    calib = {k: RNG.normal(size=(3, 4)) * 100 for k in ("P0", "P1", "P2", "P3", "Tr")}
    write_calib(tmp_path / "calib.txt", calib)
    back = read_calib(tmp_path / "calib.txt")
    assert list(back) == list(calib)
    for key, m in calib.items():
        np.testing.assert_allclose(back[key], m, rtol=1e-11)


def test_poses_round_trip(tmp_path: Path) -> None:
    poses = RNG.normal(size=(6, 3, 4))
    write_poses(tmp_path / "poses.txt", poses)
    back = read_poses(tmp_path / "poses.txt")
    assert back.shape == (6, 3, 4)
    np.testing.assert_allclose(back, poses, rtol=1e-11)


def test_predictions_round_trip(tmp_path: Path) -> None:
    ids = np.array([0, 1, 1, 7, 65535])
    path = write_predictions(tmp_path, "08", 12, ids)
    assert path == tmp_path / "sequences" / "08" / "predictions" / "000012.label"
    assert path == predictions_path(tmp_path, "08", 12)
    raw = read_label(path)
    np.testing.assert_array_equal(semantic(raw), 0)
    np.testing.assert_array_equal(raw >> 16, ids)
    np.testing.assert_array_equal(read_predictions(tmp_path, "08", 12, n_points=5), ids)
    assert leftovers(path.parent) == []


# ---------------------------------------------------------------------------------------------
# SemanticKITTI bad input
# ---------------------------------------------------------------------------------------------


def test_missing_scan(tmp_path: Path) -> None:
    with pytest.raises(FlicInputError, match="does not exist") as err:
        read_bin(tmp_path / "000000.bin")
    assert err.value.path == tmp_path / "000000.bin"
    assert "000000.bin" in str(err.value)


def test_bin_size_not_multiple_of_16(tmp_path: Path) -> None:
    path = tmp_path / "000000.bin"
    path.write_bytes(b"\0" * 1234)
    with pytest.raises(FlicInputError) as err:
        read_scan(path)
    assert str(err.value) == (
        f"{path}: size 1234 bytes is not a multiple of 16 (x, y, z, remission float32)"
    )


def test_empty_scan(tmp_path: Path) -> None:
    path = tmp_path / "000000.bin"
    path.write_bytes(b"")
    with pytest.raises(FlicInputError, match=r"is empty \(0 points\)") as err:
        read_scan(path)
    assert err.value.path == path


def test_label_count_differs_from_points(tmp_path: Path) -> None:
    write_bin(tmp_path / "000000.bin", np.ones((120, 4)))
    write_label(tmp_path / "000000.label", np.zeros(100, dtype=np.uint32))
    with pytest.raises(FlicInputError) as err:
        read_scan(tmp_path / "000000.bin", tmp_path / "000000.label")
    assert (
        str(err.value)
        == f"{tmp_path / '000000.label'}: holds 100 labels but the scan has 120 points"
    )


def test_label_size_not_multiple_of_4(tmp_path: Path) -> None:
    path = tmp_path / "000000.label"
    path.write_bytes(b"\0" * 10)
    with pytest.raises(FlicInputError, match="size 10 bytes is not a multiple of 4") as err:
        read_label(path)
    assert err.value.path == path


def test_non_finite_points_are_dropped_with_labels(tmp_path: Path) -> None:
    points = RNG.random((6, 4)).astype(np.float32)
    points[1, 0] = np.nan
    points[4, 2] = np.inf
    points[5, 3] = np.nan  # remission only: the point is kept
    write_bin(tmp_path / "x.bin", points)
    write_label(tmp_path / "x.label", np.arange(6, dtype=np.uint32))
    with pytest.warns(UserWarning, match=r"x\.bin: dropped 2 of 6 points with NaN or infinite"):
        scan = read_scan(tmp_path / "x.bin", tmp_path / "x.label")
    np.testing.assert_array_equal(scan.points, points[[0, 2, 3, 5], :3])
    np.testing.assert_array_equal(scan.labels, [0, 2, 3, 5])
    assert scan.remission.shape == (4,)


def test_scan_without_finite_points(tmp_path: Path) -> None:
    write_bin(tmp_path / "x.bin", np.full((3, 4), np.nan))
    with pytest.raises(FlicInputError, match="none of its 3 points has finite coordinates"):
        read_scan(tmp_path / "x.bin")


def reference_read_scan(bin_path: Path, label_path: Path | None) -> tuple:
    """The reader that issue 11 replaced (bytes, a copy, a mask over every point), as reference.

    Returns ``(points, remission, labels, finite, n_dropped)``.
    """
    raw = np.frombuffer(bin_path.read_bytes(), dtype="<f4").reshape(-1, 4).astype(np.float32)
    labels = None
    if label_path is not None:
        labels = np.frombuffer(label_path.read_bytes(), dtype="<u4").astype(np.uint32)
    keep = np.isfinite(raw[:, :3]).all(axis=1)
    n_bad = raw.shape[0] - int(keep.sum())
    if n_bad:
        raw = raw[keep]
        labels = None if labels is None else labels[keep]
    return raw[:, :3], raw[:, 3], labels, None if n_bad == 0 else keep, n_bad


SPECIAL = [np.nan, np.inf, -np.inf, 0.0, -0.0, 1e38, -1e-40]  # (-1e-40 is a float32 subnormal)


@pytest.mark.slow
@settings(max_examples=100, deadline=None)
@given(
    st.integers(1, 300).flatmap(
        lambda n: st.tuples(
            arrays(np.float32, (n, 4), elements=st.floats(width=32, allow_nan=False)),
            st.lists(
                st.tuples(st.integers(0, n - 1), st.integers(0, 3), st.sampled_from(SPECIAL)),
                max_size=12,
            ),
        )
    ),  # fmt: skip
    st.booleans(),
)
def test_read_scan_equals_the_reference(
    tmp_path_factory: pytest.TempPathFactory, case: tuple, with_labels: bool
) -> None:
    points, specials = case
    for i, j, v in specials:
        points[i, j] = v
    folder = tmp_path_factory.mktemp("scan")
    bin_path, label_path = folder / "x.bin", folder / "x.label"
    points.astype("<f4").tofile(bin_path)
    np.arange(points.shape[0], dtype="<u4").tofile(label_path)
    lp = label_path if with_labels else None
    ref = reference_read_scan(bin_path, lp)
    if ref[4] == points.shape[0]:
        with pytest.raises(FlicInputError, match="none of its"):
            read_scan(bin_path, lp)
        return
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scan = read_scan(bin_path, lp)
    assert len(caught) == (1 if ref[4] else 0)
    for got, want in zip(scan, ref[:4], strict=True):
        if want is None:
            assert got is None
        else:
            np.testing.assert_array_equal(got, want)
            assert got.flags.c_contiguous and got.flags.writeable and got.dtype == want.dtype
    assert scan.points.shape == (scan.remission.shape[0], 3)


def test_real_scans_equal_the_reference(kitti_root: Path) -> None:
    ds = open_dataset(kitti_root)
    for ref in ds.refs():
        scan = read_scan(ref.path, ref.label_path)
        want = reference_read_scan(ref.path, ref.label_path)
        assert want[4] == 0 and scan.finite is None
        for got, w in zip(scan[:3], want[:3], strict=True):
            np.testing.assert_array_equal(got, w)


def test_unreadable_scan(tmp_path: Path) -> None:
    (tmp_path / "000000.bin").mkdir()
    with pytest.raises(FlicInputError, match="cannot be read"):
        read_bin(tmp_path / "000000.bin")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("P0: 1 2 3\n", "line 1: P0 has 3 numbers, expected 12"),
        ("Tr: 1 2 3 4 5 6 7 8 9 10 11 x\n", "line 1: Tr: 'x' is not a number"),
        ("P0 1 2 3 4 5 6 7 8 9 10 11 12\n", "line 1: expected 'KEY: 12 numbers'"),
        ("\n\n", "holds no calibration entries"),
    ],
)
def test_malformed_calib(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "calib.txt"
    path.write_text(text)
    with pytest.raises(FlicInputError) as err:
        read_calib(path)
    assert str(err.value) == f"{path}: {message}"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0\n", "line 2: pose has 3 numbers, expected 12"),
        ("1 0 0 0 0 1 0 0 0 0 1 zero\n", "line 1: pose: 'zero' is not a number"),
        ("", "holds no poses"),
    ],
)
def test_malformed_poses(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "poses.txt"
    path.write_text(text)
    with pytest.raises(FlicInputError) as err:
        read_poses(path)
    assert str(err.value) == f"{path}: {message}"


def test_missing_calib_and_poses(tmp_path: Path) -> None:
    for read, name in ((read_calib, "calib.txt"), (read_poses, "poses.txt")):
        with pytest.raises(FlicInputError, match="does not exist") as err:
            read(tmp_path / name)
        assert err.value.path == tmp_path / name


# ---------------------------------------------------------------------------------------------
# Moosmann: img.cfg and PNG
# ---------------------------------------------------------------------------------------------


def test_img_cfg_round_trip(tmp_path: Path) -> None:
    write_img_cfg(tmp_path / "img.cfg", CFG)
    back = read_img_cfg(tmp_path / "img.cfg")
    assert (back.width, back.height, back.h_start_deg, back.h_stop_deg) == (16, 4, 180.0, -180.0)
    np.testing.assert_array_equal(back.pitch_deg, CFG.pitch_deg)
    np.testing.assert_allclose(back.elevation(), -np.radians(CFG.pitch_deg))


def test_img_cfg_real_style(tmp_path: Path) -> None:
    pitch = np.linspace(-1.9367, 24.9992, 64)
    text = "# comment\n  # another\n870; 64; 180; -180;\n" + ";".join(map(str, pitch)) + ";\n"
    (tmp_path / "img.cfg").write_text(text)
    cfg = read_img_cfg(tmp_path / "img.cfg")
    assert (cfg.width, cfg.height) == (870, 64)
    np.testing.assert_allclose(cfg.pitch_deg, pitch)
    assert cfg.elevation()[0] > 0 > cfg.elevation()[-1]


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("870; 64; 180; -180; " + "1; " * 63, "declares 64 rows but lists 63 vertical angles"),
        ("4; 2; 180; -180; 1; abc;", "field 6 'abc' is not a number"),
        ("4.5; 1; 180; -180; 1;", "image width 4.5 is not a positive integer"),
        ("# only a comment\n870; 64;", "has 2 fields, expected width; height"),
    ],
)
def test_malformed_img_cfg(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "img.cfg"
    path.write_text(text)
    with pytest.raises(FlicInputError) as err:
        read_img_cfg(path)
    assert str(err.value).startswith(f"{path}: {message}")


def test_missing_img_cfg(tmp_path: Path) -> None:
    with pytest.raises(FlicInputError, match="img.cfg: does not exist"):
        read_img_cfg(tmp_path / "img.cfg")


def test_png_round_trip_at_2mm(tmp_path: Path) -> None:
    ranges = RNG.uniform(0.5, 130.0, size=(CFG.height, CFG.width)).astype(np.float32)
    ranges[0, :3] = 0.0
    path = tmp_path / "scan00000.png"
    write_png_range(path, ranges)
    header = path.read_bytes()[:26]
    assert header[:8] == b"\x89PNG\r\n\x1a\n"
    assert (header[24], header[25]) == (16, 0)  # IHDR: bit depth 16, colour type greyscale
    back = read_png_range(path, CFG)
    assert back.dtype == np.float32 and back.shape == (CFG.height, CFG.width)
    assert np.abs(back - ranges).max() <= 0.001 + 1e-5
    assert not back[0, :3].any()


def test_png_clips_and_blanks(tmp_path: Path) -> None:
    ranges = np.zeros((CFG.height, CFG.width))
    ranges[0, :4] = [200.0, np.nan, -3.0, np.inf]
    write_png_range(tmp_path / "scan00000.png", ranges)
    back = read_png_range(tmp_path / "scan00000.png", CFG)
    np.testing.assert_allclose(back[0, :4], [65535 / 500, 0, 0, 0], rtol=1e-6)


@pytest.mark.parametrize(
    ("mode", "description"),
    [("L", "8-bit greyscale"), ("RGB", "8-bit RGB"), ("LA", "8-bit greyscale with alpha")],
)
def test_png_not_16_bit_grey(tmp_path: Path, mode: str, description: str) -> None:
    path = tmp_path / "scan00000.png"
    Image.new(mode, (CFG.width, CFG.height)).save(path)
    with pytest.raises(FlicInputError) as err:
        read_png_range(path, CFG)
    assert str(err.value) == f"{path}: is {description}, expected 16-bit greyscale"


def test_png_size_differs_from_img_cfg(tmp_path: Path) -> None:
    path = tmp_path / "scan00000.png"
    write_png_range(path, np.ones((3, 16)))
    with pytest.raises(FlicInputError) as err:
        read_png_range(path, CFG)
    assert str(err.value) == f"{path}: is 16x3 but img.cfg says 16x4"


def test_png_not_a_png(tmp_path: Path) -> None:
    garbage = tmp_path / "scan00000.png"
    garbage.write_bytes(b"definitely not an image")
    with pytest.raises(FlicInputError, match="is not an image Pillow can decode") as err:
        read_png_range(garbage, CFG)
    assert err.value.path == garbage
    jpeg = tmp_path / "scan00001.png"
    Image.new("L", (CFG.width, CFG.height)).save(jpeg, format="JPEG")
    with pytest.raises(FlicInputError, match="is a JPEG image, expected a 16-bit greyscale PNG"):
        read_png_range(jpeg, CFG)
    truncated = tmp_path / "scan00003.png"
    write_png_range(truncated, RNG.uniform(1, 100, (CFG.height, CFG.width)))
    truncated.write_bytes(truncated.read_bytes()[:80])
    with pytest.raises(FlicInputError, match="scan00003.png: cannot be decoded"):
        read_png_range(truncated, CFG)
    with pytest.raises(FlicInputError, match="scan00002.png: does not exist"):
        read_png_range(tmp_path / "scan00002.png", CFG)


# ---------------------------------------------------------------------------------------------
# SemanticKITTI dataset
# ---------------------------------------------------------------------------------------------


def test_kitti_dataset_selection(tmp_path: Path) -> None:
    root = make_kitti(tmp_path / "kitti")
    ds = SemanticKittiDataset(root)
    assert ds.format == "semantickitti" and ds.root == root
    assert [(r.sequence, r.frame) for r in ds.refs()] == [
        (s, f) for s in ("00", "01") for f in range(5)
    ]
    ds = SemanticKittiDataset(root, sequences=["01"], frames=(1, 3))
    assert [(r.sequence, r.frame) for r in ds.refs()] == [("01", 1), ("01", 2)]
    assert [r.frame for r in SemanticKittiDataset(root, ["00"], (3, None)).refs()] == [3, 4]
    assert [r.frame for r in SemanticKittiDataset(root, ["00"], (None, 2)).refs()] == [0, 1]
    ref = ds.refs()[1]
    assert ref.label_path == root / "sequences" / "01" / "labels" / "000002.label"
    frame = ds.load(ref)
    assert frame.points.shape == (10, 3) and frame.points.dtype == np.float32
    np.testing.assert_array_equal(frame.labels, 2)
    assert frame.image is None and frame.ref == ref


def test_kitti_single_sequence_folder(tmp_path: Path) -> None:
    root = make_kitti(tmp_path / "kitti", sequences=("04",))
    ds = SemanticKittiDataset(root / "sequences" / "04", sequences=["04"])
    assert [(r.sequence, r.frame) for r in ds.refs()] == [("04", f) for f in range(5)]


def test_kitti_unknown_sequence_and_empty_selection(tmp_path: Path) -> None:
    root = make_kitti(tmp_path / "kitti")
    with pytest.raises(FlicInputError) as err:
        SemanticKittiDataset(root, sequences=["05"])
    assert str(err.value) == f"{root}: no sequence 05 (found: 00, 01)"
    with pytest.raises(FlicInputError, match=r"no scans \(velodyne/\*\.bin\) in frames 10:20"):
        SemanticKittiDataset(root, frames=(10, 20))


def test_kitti_labels(tmp_path: Path) -> None:
    root = make_kitti(tmp_path / "kitti", sequences=("00",), labels=False)
    ds = SemanticKittiDataset(root)
    assert all(r.label_path is None for r in ds.refs())
    assert ds.load(ds.refs()[0]).labels is None
    with pytest.raises(FlicInputError) as err:
        SemanticKittiDataset(root, require_labels=True)
    assert str(err.value) == (
        f"{root}: missing label files: sequences/00/labels/000000.label, "
        "sequences/00/labels/000001.label, sequences/00/labels/000002.label and 2 more"
    )


# ---------------------------------------------------------------------------------------------
# Moosmann dataset
# ---------------------------------------------------------------------------------------------


def test_moosmann_gaps_and_frames(tmp_path: Path) -> None:
    log = make_log(tmp_path / "log1")
    ds = MoosmannDataset(log)
    assert ds.format == "moosmann"
    assert [(r.sequence, r.frame) for r in ds.refs()] == [("log1", 1), ("log1", 2), ("log1", 5)]
    assert [r.frame for r in MoosmannDataset(log, frames=(2, 6)).refs()] == [2, 5]
    frame = ds.load(ds.refs()[2])
    assert frame.labels is None and frame.image is not None
    assert frame.points.shape == (CFG.width, 3) and frame.points.dtype == np.float32
    np.testing.assert_allclose(np.linalg.norm(frame.points, axis=1), 5.0, rtol=1e-5)
    np.testing.assert_allclose(frame.points[:, 2], 5.0 * np.sin(np.radians(2.0)), rtol=1e-5)
    np.testing.assert_array_equal(frame.image.point_pixel, np.arange(CFG.width))


def test_moosmann_empty_frame(tmp_path: Path) -> None:
    log = make_log(tmp_path / "log", frames=(3,))
    write_png_range(log / "scan00004.png", np.zeros((CFG.height, CFG.width)))
    ds = MoosmannDataset(log)
    frame = ds.load(ds.refs()[1])
    assert frame.ref.frame == 4
    assert frame.points.shape == (0, 3) and frame.image.point_pixel.size == 0


@pytest.mark.parametrize(("cfg_in", "scans_in"), [(".", "range"), ("range", "range")])
def test_moosmann_range_subfolder(tmp_path: Path, cfg_in: str, scans_in: str) -> None:
    log = make_log(tmp_path / "drive", cfg_in=cfg_in, scans_in=scans_in)
    for root in (log, log / "range"):
        ds = open_dataset(root)
        assert isinstance(ds, MoosmannDataset)
        assert [(r.sequence, r.frame) for r in ds.refs()] == [("drive", f) for f in (1, 2, 5)]
        assert ds.load(ds.refs()[0]).points.shape == (CFG.width, 3)


def test_moosmann_folder_of_logs(tmp_path: Path) -> None:
    make_log(tmp_path / "logs" / "b", frames=(7,))
    make_log(tmp_path / "logs" / "a", frames=(1, 2), scans_in="range")
    ds = MoosmannDataset(tmp_path / "logs")
    assert [(r.sequence, r.frame) for r in ds.refs()] == [("a", 1), ("a", 2), ("b", 7)]
    assert [r.sequence for r in MoosmannDataset(tmp_path / "logs", ["b"]).refs()] == ["b"]
    with pytest.raises(FlicInputError, match=r"no sequence c \(found: a, b\)"):
        MoosmannDataset(tmp_path / "logs", ["c"])
    with pytest.raises(FlicInputError, match="no scan\\*.png frames in frames 3:5 in logs a, b"):
        MoosmannDataset(tmp_path / "logs", frames=(3, 5))


def test_moosmann_log_without_img_cfg(tmp_path: Path) -> None:
    log = make_log(tmp_path / "log")
    (log / "img.cfg").unlink()
    with pytest.raises(FlicInputError, match="holds scan\\*.png range images but no img.cfg"):
        open_dataset(log)


def test_moosmann_malformed_img_cfg_in_dataset(tmp_path: Path) -> None:
    log = make_log(tmp_path / "log")
    (log / "img.cfg").write_text("16; 4; 180; -180; 1; 2; 3;")
    with pytest.raises(FlicInputError, match="declares 4 rows but lists 3 vertical angles"):
        MoosmannDataset(log)


# ---------------------------------------------------------------------------------------------
# open_dataset, parse_frames, parse_sequences
# ---------------------------------------------------------------------------------------------


def test_open_dataset_detects_formats(tmp_path: Path) -> None:
    root = make_kitti(tmp_path / "kitti")
    assert isinstance(open_dataset(root, ["00"], (0, 1)), SemanticKittiDataset)
    assert isinstance(open_dataset(root / "sequences" / "01"), SemanticKittiDataset)
    log = make_log(tmp_path / "logs" / "log1")
    assert isinstance(open_dataset(log), MoosmannDataset)
    assert isinstance(open_dataset(tmp_path / "logs"), MoosmannDataset)
    with pytest.raises(FlicInputError, match="has no ground-truth labels"):
        open_dataset(log, require_labels=True)


def test_open_dataset_bad_paths(tmp_path: Path) -> None:
    with pytest.raises(FlicInputError) as err:
        open_dataset(tmp_path / "nowhere")
    assert str(err.value) == f"{tmp_path / 'nowhere'}: does not exist"
    (tmp_path / "other").mkdir()
    with pytest.raises(FlicInputError) as err:
        open_dataset(tmp_path / "other")
    assert str(err.value).startswith(f"{tmp_path / 'other'}: is none of: a SemanticKITTI root")


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("10:20", (10, 20)),
        ("10:", (10, None)),
        (":20", (None, 20)),
        ("7", (7, 8)),
        (":", (None, None)),
    ],
)
def test_parse_frames(text: str, expected: tuple) -> None:
    assert parse_frames(text) == expected


@pytest.mark.parametrize("text", ["abc", "1:2:3", "-1:5", "", "1.5"])
def test_parse_frames_junk(text: str) -> None:
    with pytest.raises(FlicInputError, match="invalid frame range") as err:
        parse_frames(text)
    assert err.value.path is None


def test_parse_frames_empty_range() -> None:
    with pytest.raises(FlicInputError, match="empty frame range '5:5'"):
        parse_frames("5:5")


def test_parse_sequences() -> None:
    assert parse_sequences("00,5") == ["00", "05"]
    assert parse_sequences(" 8 , log1,08") == ["08", "log1"]
    with pytest.raises(FlicInputError, match="empty name"):
        parse_sequences("00,,1")


# ---------------------------------------------------------------------------------------------
# Real data (../shared/data)
# ---------------------------------------------------------------------------------------------


def test_real_kitti_dataset(kitti_root: Path) -> None:
    ds = open_dataset(kitti_root, require_labels=True)
    refs = ds.refs()
    # every scan on disk, whatever the size of the shared set (it grew from 22 to 50 frames)
    assert len(refs) == len(list(kitti_root.glob("sequences/*/velodyne/*.bin"))) >= 50
    assert refs[0].sequence == "00" and refs[0].frame == 0
    frame = ds.load(refs[0])
    assert frame.points.shape == (124_668, 3) and frame.points.dtype == np.float32
    assert frame.labels is not None and frame.labels.shape == (124_668,)


def test_real_kitti_selection(kitti_root: Path) -> None:
    ds = open_dataset(kitti_root, sequences=["00"], frames=(1, 3))
    assert [(r.sequence, r.frame) for r in ds.refs()] == [("00", 1), ("00", 2)]


def test_real_kitti_calib_and_poses(kitti_root: Path) -> None:
    seq = kitti_root / "sequences" / "00"
    calib = read_calib(seq / "calib.txt")
    assert sorted(calib) == ["P0", "P1", "P2", "P3", "Tr"]
    poses = read_poses(seq / "poses.txt")
    assert poses.shape == (4541, 3, 4)
    np.testing.assert_allclose(poses[0, :, :3], np.eye(3), atol=1e-6)


def test_whole_dataset_evaluation_leaves_out_unlabelled_sequences(tmp_path):
    from flic_cli.io import open_dataset as open_ds

    for seq, labelled in (("00", True), ("11", False)):
        root = tmp_path / "sequences" / seq
        (root / "velodyne").mkdir(parents=True)
        np.zeros((3, 4), np.float32).tofile(root / "velodyne" / "000000.bin")
        if labelled:
            (root / "labels").mkdir()
            np.zeros(3, np.uint32).tofile(root / "labels" / "000000.label")
    with pytest.warns(UserWarning, match="sequences 11 have no labels/ folder"):
        ds = open_ds(tmp_path, require_labels=True)
    assert [r.sequence for r in ds.refs()] == ["00"]
    with pytest.raises(FlicInputError, match="missing label files"):
        open_ds(tmp_path, sequences=["00", "11"], require_labels=True)
