"""The sample's sensor profiles (``flic sample --sensor``): every profile's sequence reads back
through the SemanticKITTI reader and its ``sensor.toml`` as an image of the sensor's beams and
columns, with one label per point equal to the ray caster's truth, and the default profile is the
sample as it was."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from oracles import file_tree
from typer.testing import CliRunner

from flic_cli import sample
from flic_cli.cli import app
from flic_cli.config import load_config
from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset
from flic_cli.labels import instance, semantic
from flic_cli.sample.render import render_kitti
from flic_cli.sample.sensor import cast_full, kitti_azimuths
from flic_cli.sample.street import make_scene

runner = CliRunner()
NAMES = list(sample.SENSOR_PROFILES)
#: (beams, columns) every profile must have: the sensors' published figures.
EXPECTED = {
    "vlp16": (16, 1800),
    "vlp32c": (32, 1800),
    "hdl32e": (32, 2170),
    "hdl64e": (64, 2048),
    "os1-64": (64, 1024),
    "os1-128": (128, 2048),
    "os2-128": (128, 1024),
}


def test_the_issue_names_every_profile() -> None:
    assert sorted(NAMES) == sorted(EXPECTED)
    assert sample.DEFAULT_SENSOR == "hdl64e"
    assert sample.SENSOR_PROFILES["hdl64e"].pitch_deg is sample.HDL64_PITCH_DEG


@pytest.mark.parametrize("name", NAMES)
def test_beam_tables(name: str) -> None:
    p = sample.SENSOR_PROFILES[name]
    assert (p.beams, p.width) == EXPECTED[name]
    assert np.all(np.diff(p.pitch_deg) > 0), "rows must go from the top beam down"
    assert not p.pitch_deg.flags.writeable
    lo, hi = p.vertical_fov_deg
    assert lo == pytest.approx(-p.pitch_deg[-1]) and hi == pytest.approx(-p.pitch_deg[0])


def test_published_tables() -> None:
    """The figures of the manuals / metadata the tables come from."""
    prof = sample.SENSOR_PROFILES
    np.testing.assert_allclose(prof["vlp16"].beam_spacing_deg, 2.0)
    assert prof["vlp16"].vertical_fov_deg == pytest.approx((-15.0, 15.0))
    np.testing.assert_allclose(prof["hdl32e"].beam_spacing_deg, 4.0 / 3.0)
    assert prof["hdl32e"].vertical_fov_deg == pytest.approx((-30.67, 10.67), abs=1e-2)
    # VLP-32C: non-uniform, 1/3 deg around the horizon, 4.7 deg between its two top beams and
    # 9.4 deg between its two lowest
    v32 = prof["vlp32c"]
    assert v32.vertical_fov_deg == pytest.approx((-25.0, 15.0))
    assert v32.beam_spacing_deg.min() == pytest.approx(1 / 3, abs=1e-3)
    assert v32.beam_spacing_deg[0] == pytest.approx(15.0 - 10.333)
    assert v32.beam_spacing_deg.max() == v32.beam_spacing_deg[-1] == pytest.approx(25 - 15.639)
    # Ouster units' calibrations: OS1-64 about 0.5 deg, OS2-128 about 0.17 deg apart
    assert prof["os1-64"].vertical_fov_deg == pytest.approx((-16.75, 16.46))
    assert prof["os1-64"].beam_spacing_deg.mean() == pytest.approx(33.21 / 63)
    assert prof["os2-128"].vertical_fov_deg == pytest.approx((-11.09, 10.76))
    assert prof["os1-128"].vertical_fov_deg == pytest.approx((-22.5, 22.5))


@pytest.fixture(scope="module", params=NAMES)
def written(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory):
    name = request.param
    out = tmp_path_factory.mktemp(name) / "out"
    return name, sample.write_sample(out, frames=2, seed=1, sensor=name)


@pytest.mark.slow
def test_written_layout(written) -> None:
    name, paths = written
    out = paths.kitti_root.parent
    seq = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    frames = {
        f"semantickitti/sequences/00/{d}/00000{k}.{e}"
        for k in (0, 1)
        for d, e in (("velodyne", "bin"), ("labels", "label"))
    }
    txt = {f"semantickitti/sequences/00/{t}.txt" for t in ("calib", "poses", "times")}
    if name == "hdl64e":
        assert paths.config is None and paths.moosmann_log == out / "moosmann"
        assert seq == frames | txt | {"moosmann/img.cfg"} | {
            f"moosmann/scan0000{k}.png" for k in (0, 1)
        }
    else:
        assert paths.config == out / "sensor.toml" and paths.moosmann_log is None
        assert seq == frames | txt | {"sensor.toml"}
        with pytest.raises(ValueError, match="no Moosmann log"):
            paths.moosmann_truth(0)
    assert paths.sensor == name and paths.kitti_width == EXPECTED[name][1]


@pytest.mark.slow
def test_round_trip_through_the_reader(written) -> None:
    """Reader + the sample's own ``--config``: rows = beams, width = columns, ring recovery, the
    rows at the table's elevations, one pixel per point at the cast's range, and every point's
    label the caster's class and instance of its ray."""
    name, paths = written
    beams, width = EXPECTED[name]
    cfg = load_config(paths.config)  # None: the default config (64 x 2048)
    assert (cfg.projection.rows, cfg.projection.width, cfg.projection.mode) == (
        beams,
        width,
        "rings",
    )
    profile = sample.SENSOR_PROFILES[name]
    ds = open_dataset(paths.kitti_root, require_labels=True)
    for ref in ds.refs():
        frame = ds.load(ref)
        n = frame.points.shape[0]
        assert frame.labels.shape == (n,)
        image = cfg.projection(frame.points)
        assert image.projection == "rings"
        assert image.ranges.shape == (beams, width)
        np.testing.assert_allclose(-np.degrees(image.elevation), profile.pitch_deg, atol=1e-3)
        # the caster's truth, with the writer's noise stream
        rng = np.random.default_rng([paths.seed, ref.frame, 1])
        az = kitti_azimuths(width)
        ranges, sem, inst, _ = cast_full(make_scene(paths.seed, ref.frame), profile.pitch_deg,
                                         az, rng)  # fmt: skip
        valid = ranges > 0
        assert n == int(valid.sum()) == int((image.ranges > 0).sum())
        # column k of the cast is image column W/2 - 1 - k (counter-clockwise from behind)
        cols = (width // 2 - 1 - np.arange(width)) % width
        np.testing.assert_allclose(image.ranges[:, cols], ranges, rtol=1e-5, atol=1e-5)
        np.testing.assert_array_equal(semantic(frame.labels), sem[valid])
        np.testing.assert_array_equal(instance(frame.labels), inst[valid])
        assert len(np.unique(instance(frame.labels))) > 10  # the street's objects are there


@pytest.mark.slow
def test_sensor_toml_is_a_config(written) -> None:
    name, paths = written
    if paths.config is None:
        pytest.skip("the default profile needs no config")
    text = paths.config.read_text()
    assert text.startswith(f"# flic sample --sensor {name}: ")
    elev = text.split("top beam first (= image row 0 first): ")[1].split("\n")[0]
    np.testing.assert_allclose(
        [float(v) for v in elev.split(",")], -sample.SENSOR_PROFILES[name].pitch_deg, atol=5e-4
    )


@pytest.mark.slow
def test_default_profile_is_the_sample_as_before(tmp_path: Path) -> None:
    """``--sensor hdl64e`` is the default sample, and its scans are what the sample cast before
    the profiles existed: the HDL-64E table, 2048 columns, the noise stream ``[seed, frame, 1]``."""
    plain = sample.write_sample(tmp_path / "plain", frames=2)
    named = sample.write_sample(tmp_path / "named", frames=2, sensor="hdl64e")
    a, b = file_tree(tmp_path / "plain"), file_tree(tmp_path / "named")
    assert a == b
    assert "sensor.toml" not in a and plain.config is None
    for k in range(2):
        rng = np.random.default_rng([0, k, 1])
        pts, labels = render_kitti(make_scene(0, k), width=2048, noise=True, rng=rng)
        assert a[f"semantickitti/sequences/00/velodyne/00000{k}.bin"] == pts.tobytes()
        assert a[f"semantickitti/sequences/00/labels/00000{k}.label"] == labels.tobytes()
    assert named.moosmann_truth(0)[0].shape == (64, 870)


@pytest.mark.slow
def test_a_profile_sample_replaces_another(tmp_path: Path) -> None:
    out = tmp_path / "out"
    sample.write_sample(out, frames=1, sensor="vlp16")
    sample.write_sample(out, frames=1, sensor="os2-128")  # a sample: may be replaced
    assert "os2-128" in (out / "sensor.toml").read_text()
    sample.write_sample(out, frames=1)  # and back to the default
    assert not (out / "sensor.toml").exists() and (out / "moosmann" / "img.cfg").is_file()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(FlicInputError, match="other files than a flic sample"):
        sample.write_sample(out, frames=1, sensor="vlp16")


def test_unknown_sensor_is_one_line_and_writes_nothing(tmp_path: Path) -> None:
    with pytest.raises(FlicInputError) as err:
        sample.write_sample(tmp_path / "out", frames=1, sensor="hdl16")
    assert "\n" not in str(err.value) and "--sensor hdl16" in str(err.value)
    assert "vlp16" in str(err.value)
    assert list(tmp_path.iterdir()) == []
    result = runner.invoke(app, ["sample", str(tmp_path / "out"), "--sensor", "hdl16"])
    assert result.exit_code == 2 and "unknown sensor" in result.output
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_cli_writes_a_profile_that_evaluate_reads(tmp_path: Path) -> None:
    out = tmp_path / "vlp16"
    result = runner.invoke(app, ["sample", str(out), "--sensor", "vlp16", "--frames", "1"])
    assert result.exit_code == 0, result.output
    assert f"--config {out / 'sensor.toml'}" in result.output
    args = ["evaluate", str(out / "semantickitti"), "--config", str(out / "sensor.toml")]
    args += ["--methods", "flic0", "--setting", "no-ground", "--out", str(tmp_path / "e")]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    objects = (tmp_path / "e" / "per_object.csv").read_text().splitlines()
    assert len(objects) > 5  # header + the frame's objects of at least 100 points


def test_bridge_parameters_follow_the_beam_gap() -> None:
    """Bridge's far link distance covers adjacent beams on a facing surface by the rule's margin;
    only the VLP-16 (2 deg beams) needs more than the defaults."""
    from flic_cli.methods.bridge import Bridge
    from flic_cli.sensor_params import (
        BRIDGE_GAPS_PER_GAMMA,
        bridge_parameters,
        street_beam_gap_deg,
    )

    def elevation(name: str) -> np.ndarray:
        return -np.radians(sample.SENSOR_PROFILES[name].pitch_deg)

    for name in sample.SENSOR_PROFILES:
        derived = bridge_parameters(elevation(name))
        gamma = derived.get("gamma_deg", Bridge.gamma_deg)
        gap = np.radians(street_beam_gap_deg(elevation(name)))
        # d sin(gamma) against the gap 2 d sin(gap / 2) of a surface facing the sensor
        margin = np.sin(np.radians(gamma)) / (2.0 * np.sin(gap / 2.0))
        assert margin >= BRIDGE_GAPS_PER_GAMMA * 0.99, name
        assert (name == "vlp16") == bool(derived), name
    # the VLP-16's beams are 2 deg apart: the defaults' d sin(2 deg) is just one gap
    assert street_beam_gap_deg(elevation("vlp16")) == pytest.approx(2.0)
    assert np.sin(np.radians(2.0)) < 2.0 * np.sin(np.radians(1.0))
    derived = bridge_parameters(elevation("vlp16"))
    assert derived == {"gamma_deg": 3.0, "threshold_m": 0.52}  # 10 m sin(3 deg) = 0.523 m
    # the order of the beams does not matter; the sky beams (above +3 deg) do not count
    assert bridge_parameters(elevation("vlp16")[::-1]) == derived
    sky = np.radians([30.0, 20.0, 10.0])
    assert bridge_parameters(np.concatenate([sky, elevation("hdl64e")])) == {}
    with pytest.raises(ValueError, match="fewer than two beams"):
        street_beam_gap_deg(sky)


@pytest.mark.slow
def test_sensor_toml_names_the_derived_bridge_and_sets_none(tmp_path: Path) -> None:
    """A profile's sensor.toml sets no method parameter (every run derives them from the data,
    tests/test_sensor_params.py); its comment names the values the rule gives."""
    from flic_cli.methods.bridge import Bridge

    v16 = sample.write_sample(tmp_path / "v16", frames=1, sensor="vlp16")
    tomllib = pytest.importorskip("tomllib" if sys.version_info >= (3, 11) else "tomli")

    text = v16.config.read_text()
    assert "methods" not in tomllib.loads(text) and "# gamma_deg = 3.0, threshold_m = 0.52" in text
    assert load_config(v16.config).methods["bridge"].method == Bridge()
    h32 = sample.write_sample(tmp_path / "h32", frames=1, sensor="hdl32e")
    assert "methods" not in tomllib.loads(h32.config.read_text())
    assert "gamma_deg" not in h32.config.read_text()
