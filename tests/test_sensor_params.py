"""Parameters that follow the sensor (flic_cli.sensor_params): derived once per dataset when the
runs build their components, the config's values winning, the HDL-64E keeping the defaults."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flic_cli import sample
from flic_cli.cli import app
from flic_cli.config import load_config
from flic_cli.io import open_dataset
from flic_cli.methods.bridge import Bridge
from flic_cli.sensor_params import (
    RUN_GROUND_RANGE_M,
    RUN_JUMP_FLOOR,
    RUN_JUMP_MARGIN,
    BeamTable,
    column_run_jumps,
    for_beams,
    for_dataset,
)

runner = CliRunner()


def _elevation(name: str) -> np.ndarray:
    return -np.radians(sample.SENSOR_PROFILES[name].pitch_deg)


@pytest.fixture(scope="module")
def vlp16(tmp_path_factory: pytest.TempPathFactory) -> sample.SamplePaths:
    return sample.write_sample(tmp_path_factory.mktemp("v16") / "v16", frames=1, sensor="vlp16")


def test_runs_derive_bridge_from_the_data(vlp16: sample.SamplePaths) -> None:
    """The VLP-16's rows (recovered from the scan, elevations estimated from its points) give
    Bridge 1.5 beam gaps, as the beam table itself does; every Bridge variant takes them."""
    config = load_config(vlp16.config)
    ds = open_dataset(vlp16.kitti_root)
    derived = for_dataset(config, ds, ds.refs())
    bridge = derived.methods["bridge"].method
    assert (bridge.gamma_deg, bridge.threshold_m) == (3.0, 0.52)
    assert bridge.reach_px == Bridge.reach_px and bridge.min_size == Bridge.min_size
    # the other methods are untouched
    for name, spec in config.methods.items():
        if spec.kind != "bridge":
            assert derived.methods[name] == spec, name
    # from the table itself: the same
    table = for_beams(config, BeamTable(_elevation("vlp16"), 1800))[0]
    assert table.methods["bridge"].method == bridge


def test_a_value_the_config_sets_wins(tmp_path: Path, vlp16: sample.SamplePaths) -> None:
    user = tmp_path / "user.toml"
    user.write_text(
        (vlp16.config.read_text())
        + "\n[methods.bridge]\ngamma_deg = 2.5\n"
        + '\n[methods.bridge-fixed]\nkind = "bridge"\nthreshold_m = 0.35\ngamma_deg = 2.0\n'
        + '\n[methods.bridge-near]\nlike = "bridge-fixed"\nthreshold_m = 0.4\n'
    )
    config = load_config(user)
    assert config.methods["bridge-near"].given == {"threshold_m", "gamma_deg"}
    ds = open_dataset(vlp16.kitti_root)
    derived = for_dataset(config, ds, ds.refs())
    # gamma set: threshold_m (derived from gamma by the same rule) keeps its value too
    assert derived.methods["bridge"].method == Bridge(gamma_deg=2.5)
    assert derived.methods["bridge-fixed"].method == Bridge(threshold_m=0.35, gamma_deg=2.0)
    assert derived.methods["bridge-near"].method == Bridge(threshold_m=0.4, gamma_deg=2.0)


@pytest.mark.parametrize("name", [n for n in sample.SENSOR_PROFILES if n != "vlp16"])
def test_beams_at_most_1p33_deg_apart_keep_the_defaults(name: str) -> None:
    config = load_config()
    profile = sample.SENSOR_PROFILES[name]
    out, applied = for_beams(config, BeamTable(_elevation(name), profile.width))
    assert applied == {} and out is config


def test_the_default_sample_keeps_every_default() -> None:
    """The HDL-64E sample (and so SemanticKITTI's labels): the derived config is the config."""
    config = load_config()
    ds = open_dataset(sample.ensure_sample().kitti_root)
    assert for_dataset(config, ds, ds.refs()[:1]) is config
    for name in ("hdl64e", "os1-64", "os1-128", "os2-128"):
        jumps = column_run_jumps(_elevation(name))
        assert np.all(jumps == RUN_JUMP_FLOOR), name


@pytest.mark.parametrize("name", list(sample.SENSOR_PROFILES))
def test_run_jumps_admit_level_ground_between_adjacent_beams(name: str) -> None:
    """Brute force over the rows: where the row above sees level ground within the range the
    rule covers, the limit admits the ground's own growth to it with the margin; elsewhere it
    is the floor; never below the floor."""
    el = _elevation(name)
    h = 1.73
    jumps = column_run_jumps(el, h)
    assert jumps.shape == el.shape and not jumps.flags.writeable
    for r in range(1, el.size):
        lower, upper = el[r], el[r - 1]
        if upper < 0 and lower < upper and h / np.tan(-upper) <= RUN_GROUND_RANGE_M:
            growth = (h / np.tan(-upper)) / (h / np.tan(-lower)) - 1.0
            assert jumps[r] == pytest.approx(max(RUN_JUMP_FLOOR, growth + RUN_JUMP_MARGIN))
        else:
            assert jumps[r] == RUN_JUMP_FLOOR
    # the VLP-32C's two lowest beams: 3.7 m to 6.2 m on level ground, far beyond 0.3
    if name == "vlp32c":
        growth = np.tan(np.radians(25.0)) / np.tan(np.radians(15.639)) - 1.0
        assert jumps[-1] == pytest.approx(growth + RUN_JUMP_MARGIN, abs=1e-3)
        assert growth > 0.6


def _run_jumps_whole_array(el: np.ndarray, h: float) -> np.ndarray:
    """The rule as whole-array numpy operations (how column_run_jumps computed it until its
    per-frame cost showed in flic benchmark): the reference the loop must match bit for bit."""
    out = np.full(el.size, RUN_JUMP_FLOOR)
    lower, upper = el[1:], el[:-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = h / np.tan(-upper)
        growth = np.tan(-lower) / np.tan(-upper) - 1.0
    use = (upper < 0.0) & (lower < upper) & (reach <= RUN_GROUND_RANGE_M)
    out[1:] = np.where(use, np.maximum(RUN_JUMP_FLOOR, growth + RUN_JUMP_MARGIN), RUN_JUMP_FLOOR)
    return out


def test_run_jumps_equal_the_whole_array_rule_bit_for_bit() -> None:
    """Every sample profile and random tables (sorted like a sensor's, unsorted, with a NaN
    row, several heights): the same float64 values as the whole-array form, so that no
    decision of the remover moves."""
    rng = np.random.default_rng(7)
    tables = [_elevation(name) for name in sample.SENSOR_PROFILES]
    for k in range(300):
        n = int(rng.integers(2, 130))
        el = np.sort(rng.uniform(-0.8, 0.3, n))[::-1].copy()
        if k % 3 == 0:
            el = rng.uniform(-1.7, 1.7, n)
        if k % 7 == 0:
            el[rng.integers(0, n)] = np.nan
        tables.append(el)
    raised = 0
    for el in tables:
        for h in (0.5, 1.73, 2.5):
            want = _run_jumps_whole_array(el, h)
            raised += int(np.any(want > RUN_JUMP_FLOOR))
            assert np.array_equal(column_run_jumps(el, h), want)
    assert raised > 100  # the raised rows are exercised, not only the floor


def test_column_keeps_the_vlp32c_bottom_rows(tmp_path: Path) -> None:
    """On a VLP-32C frame the derived limits find the ground of the two lowest rows, which the
    fixed 0.3 lost (their runs ended at the next beam's ground); a config's run_jump wins."""
    from flic_cli.classes import ground_mask
    from flic_cli.ground.column import ColumnGround
    from flic_cli.runs.pipeline import prepare

    paths = sample.write_sample(tmp_path / "v32", frames=1, sensor="vlp32c")
    config = load_config(paths.config)
    ds = open_dataset(paths.kitti_root)
    prep = prepare(ds.load(ds.refs()[0]), "ground", config.projection)
    truth = ground_mask(prep.labels)
    w = prep.image.shape[1]
    bottom = (prep.image.point_pixel >= 0) & (prep.image.point_pixel // w >= 30) & truth

    def recall(remover: ColumnGround) -> tuple[float, float]:
        decided = remover.extract(prep.image, prep.points).decided
        return decided[truth].mean(), decided[bottom].mean()

    assert np.all(ColumnGround(run_jump=0.3).run_jumps(prep.image) == 0.3)
    fixed, fixed_bottom = recall(ColumnGround(run_jump=0.3))
    derived, derived_bottom = recall(ColumnGround())
    assert fixed_bottom < 0.05 and derived_bottom > 0.5
    assert derived > fixed + 0.2


def test_evaluate_records_the_derived_parameters(tmp_path: Path, vlp16: sample.SamplePaths) -> None:
    args = ["evaluate", str(vlp16.kitti_root), "--config", str(vlp16.config), "--frames", "0:1"]
    args += ["--methods", "bridge", "--setting", "no-ground", "--out", str(tmp_path / "e")]
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    run = json.loads((tmp_path / "e" / "run.json").read_text())
    table = json.dumps(run)
    assert '"gamma_deg": 3.0' in table and '"threshold_m": 0.52' in table


@pytest.mark.parametrize(
    ("path", "bridge"),
    [
        ("sensors/velodyne/vlp16_velodyne_example.pcap", Bridge(gamma_deg=3.0, threshold_m=0.52)),
        ("sensors/ouster/OS-2-128-U1_v2.3.0_1024x10.pcap", Bridge()),
        ("semantickitti/sequences/00", Bridge()),
    ],
)
def test_real_recordings_derive_from_their_sensor_model(
    shared_data: Path, path: str, bridge: Bridge
) -> None:
    """The VLP-16 capture's decoder table (2 deg beams) derives Bridge's VLP-16 values; the
    OS-2-128's metadata and the SemanticKITTI scans' recovered rows keep the defaults."""
    config = load_config()
    ds = open_dataset(shared_data / path, None, (0, 1))
    assert for_dataset(config, ds, ds.refs()).methods["bridge"].method == bridge


def test_info_prints_what_runs_derive(shared_data: Path) -> None:
    sensors = shared_data / "sensors"
    result = runner.invoke(app, ["info", str(sensors / "velodyne/vlp16_velodyne_example.pcap")])
    assert result.exit_code == 0, result.output
    assert "derived for Bridge: gamma_deg = 3, threshold_m = 0.52" in result.output
    assert "derived for column: run limit above 4 row(s) raised to at most 0.769" in result.output
    result = runner.invoke(app, ["info", str(sensors / "ouster/OS-2-128-U1_v2.3.0_1024x10.pcap")])
    assert result.exit_code == 0, result.output
    assert "derived for Bridge: its defaults" in result.output
    assert "derived for column: run limit 0.3 on every row" in result.output
