"""`flic segment` end to end, on the synthetic sample and the real frames, and its errors."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

from flic_cli.cli import app
from flic_cli.io import open_dataset, read_predictions

runner = CliRunner()
METHODS = ["flic0", "flic1", "flic6", "flic14", "bogoslavskyi", "dbscan"]


def _segment(*args: str):
    return runner.invoke(app, ["segment", *map(str, args)])


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_segment_writes_a_label_file_per_frame(small_sample, tmp_path, method):
    result = _segment(small_sample.kitti_root, "--method", method, "--out", tmp_path)
    assert result.exit_code == 0, result.output
    assert "segmented 3 frames" in result.output
    ds = open_dataset(small_sample.kitti_root)
    for ref in ds.refs():
        n = ds.load(ref).points.shape[0]
        pred = read_predictions(tmp_path, ref.sequence, ref.frame, n_points=n)
        raw = np.fromfile(
            tmp_path / "sequences" / ref.sequence / "predictions" / f"{ref.frame:06d}.label",
            dtype="<u4",
        )
        assert np.all(raw & 0xFFFF == 0) and np.array_equal(raw >> 16, pred)
        assert pred.max() >= 5  # the street has cars, walls and trees


@pytest.mark.slow
def test_mc_option_selects_the_preset(small_sample, tmp_path):
    a = _segment(small_sample.kitti_root, "--method", "flic", "--mc", "14", "--out", tmp_path / "a")
    b = _segment(small_sample.kitti_root, "--method", "flic14", "--out", tmp_path / "b")
    assert a.exit_code == b.exit_code == 0
    pa = read_predictions(tmp_path / "a", "00", 0)
    assert np.array_equal(pa, read_predictions(tmp_path / "b", "00", 0))


@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_segment_moosmann_log(small_sample, tmp_path, method):
    """Moosmann predictions are 16-bit label images named after their range images, holding
    exactly the labels of the method on that image."""
    from flic_cli.config import load_config
    from flic_cli.io.moosmann import label_image_path, read_label_image
    from flic_cli.runs.pipeline import build_segmenter

    result = _segment(
        small_sample.moosmann_log, "--method", method, "--out", tmp_path, "--render", 1
    )
    assert result.exit_code == 0, result.output
    ds = open_dataset(small_sample.moosmann_log)
    seg = build_segmenter(load_config(), method, "ground", "own")
    for ref in ds.refs():
        path = label_image_path(tmp_path, ref.sequence, ref.path)
        assert path.name == ref.path.stem + ".label.png"
        got = read_label_image(path, ds._cfg[ref.sequence])
        frame = ds.load(ref)
        labels, _ = seg(frame.image, frame.points)
        expected = np.zeros(frame.image.ranges.size, dtype=np.int64)
        expected[frame.image.point_pixel] = labels
        np.testing.assert_array_equal(got.reshape(-1), expected)
    assert list(tmp_path.glob("render_*_000001.png")) and list(tmp_path.glob("views_*_000001.png"))
    assert not list(tmp_path.rglob("*.label"))


@pytest.mark.slow
def test_no_ground_setting_drops_ground_classes(small_sample, tmp_path):
    result = _segment(small_sample.kitti_root, "--setting", "no-ground", "--out", tmp_path)
    assert result.exit_code == 0, result.output
    frame = open_dataset(small_sample.kitti_root).load(
        open_dataset(small_sample.kitti_root).refs()[0]
    )
    pred = read_predictions(tmp_path, "00", 0)
    ground = np.isin(frame.labels & 0xFFFF, [40, 44, 48, 49, 60, 72])
    assert pred[ground].max() == 0 and pred[~ground].max() > 0


@pytest.mark.slow
def test_segment_real_frames_with_every_method(kitti_root, tmp_path):
    for method in ["flic0", "flic14", "bogoslavskyi"]:
        result = _segment(
            kitti_root,
            "--sequences",
            "04",
            "--frames",
            "0:2",
            "--method",
            method,
            "--out",
            tmp_path / method,
            "--render",
            0,
        )
        assert result.exit_code == 0, result.output
        assert "segmented 2 frames" in result.output
        assert (tmp_path / method / "render_04_000000.png").stat().st_size > 1000
    result = _segment(
        kitti_root,
        "--sequences",
        "01",
        "--frames",
        "0:1",
        "--method",
        "dbscan",
        "--setting",
        "no-ground",
        "--out",
        tmp_path / "dbscan",
    )
    assert result.exit_code == 0, result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["/nonexistent/data"], "/nonexistent/data: does not exist"),
        (["{kitti}", "--method", "nope"], "unknown method 'nope'"),
        (["{kitti}", "--method", "dbscan", "--mc", "6"], "--mc applies to --method flic only"),
        (["{moos}", "--setting", "no-ground"], "has no ground-truth labels"),
        (["{kitti}", "--frames", "x:y"], "invalid frame range"),
        (["{kitti}", "--sequences", "07"], "no sequence 07"),
        (["{kitti}", "--out", "{file}/out"], "cannot be created"),
        (["{kitti}", "--config", "{file}"], "is not valid TOML"),
    ],
)
def test_bad_input_is_one_line_exit_2(small_sample, tmp_path, args, message):
    blocker = tmp_path / "file.txt"
    blocker.write_text("this is [not toml\n")
    fill = {
        "kitti": small_sample.kitti_root,
        "moos": small_sample.moosmann_log,
        "file": blocker,
    }
    args = [a.format(**fill) for a in args]
    if "--out" not in args:
        args += ["--out", str(tmp_path / "out")]
    result = _segment(*args)
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(lines) == 1 and message in lines[0], result.output
    assert "Traceback" not in result.output


@pytest.mark.slow
def test_spherical_projection_by_config(small_sample, tmp_path):
    cfg = tmp_path / "spherical.toml"
    cfg.write_text('[projection]\nmode = "spherical"\n')
    result = _segment(small_sample.kitti_root, "--config", cfg, "--out", tmp_path / "s")
    assert result.exit_code == 0, result.output
    rings = _segment(small_sample.kitti_root, "--out", tmp_path / "r")
    coverage = [float(r.output.split("coverage ")[1].split("%")[0]) for r in (result, rings)]
    assert coverage[0] < coverage[1]  # the synthetic scan is in sensor order: rings cover more


@pytest.mark.slow
def test_empty_moosmann_frame_is_segmented_to_nothing(small_sample, tmp_path):
    import shutil

    from flic_cli.io.moosmann import write_png_range

    log = tmp_path / "log"
    shutil.copytree(small_sample.moosmann_log, log)
    write_png_range(log / "scan00001.png", np.zeros((64, 870), np.float32))
    result = _segment(log, "--out", tmp_path / "out")
    assert result.exit_code == 0, result.output
    from flic_cli.io.moosmann import label_image_path, read_img_cfg, read_label_image

    image = read_label_image(
        label_image_path(tmp_path / "out", "log", "scan00001.png"), read_img_cfg(log / "img.cfg")
    )
    assert image.shape == (64, 870) and not image.any()


@pytest.mark.slow
@pytest.mark.parametrize("setting", ["ground", "no-ground"])
def test_predictions_hold_one_label_per_stored_point_with_nan_points(
    small_sample, tmp_path, setting
):
    """Points with NaN/inf coordinates are dropped for segmenting, but the prediction still has
    one label per point of the .bin (SemanticKITTI's rule); the dropped points get 0."""
    from flic_cli.io import read_bin, read_label, write_bin, write_label

    seq = tmp_path / "data" / "sequences" / "00"
    src = small_sample.kitti_root / "sequences" / "00"
    raw = read_bin(src / "velodyne" / "000000.bin")
    bad = np.arange(0, raw.shape[0], 97)
    raw[bad, 0] = np.nan
    raw[bad[::2], 2] = np.inf
    write_bin(seq / "velodyne" / "000000.bin", raw)
    write_label(seq / "labels" / "000000.label", read_label(src / "labels" / "000000.label"))
    result = _segment(tmp_path / "data", "--setting", setting, "--out", tmp_path / "out")
    assert result.exit_code == 0, result.output
    assert f"warning: {seq / 'velodyne' / '000000.bin'}: dropped {bad.size} of" in result.output
    pred = read_predictions(tmp_path / "out", "00", 0, n_points=raw.shape[0])
    assert pred.shape == (raw.shape[0],)
    assert np.all(pred[bad] == 0) and pred.max() > 0


@pytest.mark.slow
def test_spherical_fallback_is_named_for_every_frame_and_counted(small_sample, tmp_path, capsys):
    """A scan whose points are not in sensor order cannot give rings: each such frame gets a
    warning naming its file, and the summary counts them."""
    import shutil

    from flic_cli.cli import main

    root = tmp_path / "kitti"
    shutil.copytree(small_sample.kitti_root, root)
    rng = np.random.default_rng(0)
    for frame in (0, 2):
        path = root / "sequences" / "00" / "velodyne" / f"{frame:06d}.bin"
        raw = np.fromfile(path, dtype="<f4").reshape(-1, 4)
        order = rng.permutation(raw.shape[0])
        raw[order].tofile(path)
        lab = root / "sequences" / "00" / "labels" / f"{frame:06d}.label"
        np.fromfile(lab, dtype="<u4")[order].tofile(lab)
    with pytest.raises(SystemExit) as info:
        main(["segment", str(root), "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert info.value.code == 0, captured.err
    warned = [ln for ln in captured.err.splitlines() if "ring recovery" in ln]
    assert [ln.split(":")[1].strip() for ln in warned] == [
        str(root / "sequences" / "00" / "velodyne" / f"{f:06d}.bin") for f in (0, 2)
    ]
    assert "2 frame(s) projected spherically" in captured.out


@pytest.mark.slow
def test_semantics_oracle_and_a_network_folder(small_sample, tmp_path):
    """--semantics writes the classes in the lower 16 bits; only thing points are clustered
    (ids in the upper bits); stuff points carry instance 0; a network's folder is read."""
    from flic_cli.classes import THING_LUT
    from flic_cli.io import read_label, write_label

    root = small_sample.kitti_root
    result = _segment(root, "--semantics", "oracle", "--method", "flic14", "--out", tmp_path / "o")
    assert result.exit_code == 0, result.output
    gt = read_label(root / "sequences" / "00" / "labels" / "000000.label")
    pred = np.fromfile(tmp_path / "o" / "sequences" / "00" / "predictions" / "000000.label", "<u4")
    np.testing.assert_array_equal(pred & 0xFFFF, gt & 0xFFFF)
    thing = THING_LUT[gt & 0xFFFF]
    assert np.all(pred[~thing] >> 16 == 0) and (pred[thing] >> 16 > 0).all()

    # a "network" that calls every car a building: cars are no longer clustered
    net = tmp_path / "net"
    for ref in open_dataset(root).refs():
        labels = read_label(ref.label_path) & 0xFFFF
        labels[labels == 10] = 50
        write_label(net / "sequences" / "00" / "predictions" / f"{ref.frame:06d}.label", labels)
    result = _segment(root, "--semantics", net, "--out", tmp_path / "n")
    assert result.exit_code == 0, result.output
    pred = np.fromfile(tmp_path / "n" / "sequences" / "00" / "predictions" / "000000.label", "<u4")
    cars = (gt & 0xFFFF) == 10
    assert cars.any() and np.all(pred[cars] == 50)


@pytest.mark.slow
def test_export_ply(small_sample, tmp_path):
    from plyfile import PlyData

    result = _segment(
        small_sample.kitti_root, "--frames", "0:2", "--export", "ply", "--out", tmp_path
    )
    assert result.exit_code == 0, result.output
    pred = read_predictions(tmp_path, "00", 1)
    ply = PlyData.read(tmp_path / "sequences" / "00" / "ply" / "000001.ply")["vertex"]
    np.testing.assert_array_equal(ply["cluster"], pred)  # ground setting: every point kept
    assert {"x", "y", "z", "red", "green", "blue"} <= set(ply.data.dtype.names)
