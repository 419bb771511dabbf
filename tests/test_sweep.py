"""`flic sweep-threshold`: one row per value, each equal to `flic evaluate` at that value."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from flic_cli.cli import app
from flic_cli.config import load_config
from flic_cli.errors import FlicInputError
from flic_cli.methods import KINDS
from flic_cli.runs.evaluate import run_evaluate
from flic_cli.runs.spec import EvaluateRun, Selection
from flic_cli.runs.sweep import SWEEP_COLUMNS, sweep_values

runner = CliRunner()


def _sweep(data: Path, out: Path, *extra: str):
    return runner.invoke(app, ["sweep-threshold", str(data), "--out", str(out), *extra])


def _evaluate_at(
    data: Path, out: Path, method: str, param: str, value: float, setting: str, frames=None
) -> pd.Series:
    override = out.parent / f"{out.name}.toml"
    override.write_text(f"[methods.{method}]\n{param} = {value!r}\n")
    cfg = load_config(override)
    sel = Selection(data, frames=frames, setting=setting, config=cfg, progress=False)
    run_evaluate(EvaluateRun(sel, out, [method]))
    return pd.read_csv(out / "per_setting.csv").iloc[0]


@pytest.mark.slow
@pytest.mark.parametrize("setting", ["no-ground", "ground"])
def test_flic_sweep_equals_evaluate(sample_root: Path, tmp_path: Path, setting: str) -> None:
    out = tmp_path / "sweep"
    result = _sweep(
        sample_root,
        out,
        "--method",
        "flic",
        "--mc",
        "0",
        "--from",
        "0.4",
        "--to",
        "0.8",
        "--step",
        "0.2",
        "--setting",
        setting,
    )
    assert result.exit_code == 0, result.output
    assert "best threshold_m" in result.output
    table = pd.read_csv(out / "sweep.csv")
    assert list(table.columns) == list(SWEEP_COLUMNS)
    assert table["value"].tolist() == [0.4, 0.6, 0.8]
    assert (table["param"] == "threshold_m").all()
    assert (out / "sweep.png").stat().st_size > 1000
    row = table[table["value"] == 0.6].iloc[0]
    ev = _evaluate_at(sample_root, tmp_path / "ev", "flic0", "threshold_m", 0.6, setting)
    for key in ("iou_mu", "p_mu", "p_0.50", "p_0.75", "p_0.95", "objects"):
        assert row[key] == pytest.approx(ev[key], abs=1e-9), key


@pytest.mark.slow
def test_bogoslavskyi_and_dbscan_parameters(sample_root: Path, tmp_path: Path) -> None:
    out = tmp_path / "b"
    result = _sweep(
        sample_root, out, "--method", "bogoslavskyi", "--from", "8", "--to", "12", "--step", "2",
        "--frames", "0:1", "--jobs", "2",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "sweep.csv")
    assert table["value"].tolist() == [8.0, 10.0, 12.0]
    assert (table["param"] == "angle_deg").all()
    ev = _evaluate_at(
        sample_root, tmp_path / "ev", "bogoslavskyi", "angle_deg", 10.0, "no-ground", (0, 1)
    )
    assert table.loc[1, "iou_mu"] == pytest.approx(ev["iou_mu"], abs=1e-9)

    out = tmp_path / "d"
    result = _sweep(
        sample_root, out, "--method", "dbscan", "--from", "0.5", "--to", "0.6", "--step", "0.1",
        "--frames", "0:1",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "sweep.csv")
    assert table["value"].tolist() == [0.5, 0.6]
    assert (table["param"] == "eps_m").all()
    assert (out / "sweep.png").is_file()


def test_sweep_values() -> None:
    flic = sweep_values(*KINDS["flic"].sweep_range)
    assert flic.size == 27 and flic[0] == 0.2 and flic[-1] == 1.5
    assert np.allclose(np.diff(flic), 0.05)
    angles = sweep_values(*KINDS["bogoslavskyi"].sweep_range)
    assert angles.tolist() == list(map(float, range(2, 31)))
    assert sweep_values(*KINDS["dbscan"].sweep_range).size == 14
    for bad in ((0.5, 0.2, 0.1), (0.2, 0.5, 0.0), (0.0, 0.5, 0.1)):
        with pytest.raises(FlicInputError):
            sweep_values(*bad)


def test_bad_sweep_options(sample_root: Path, tmp_path: Path) -> None:
    result = _sweep(sample_root, tmp_path / "x", "--from", "1.0", "--to", "0.5")
    assert result.exit_code == 2 and "--to" in result.output
    result = _sweep(sample_root, tmp_path / "x", "--method", "dbscan", "--mc", "1")
    assert result.exit_code == 2 and "--mc" in result.output
    result = _sweep(sample_root, tmp_path / "x", "--setting", "both")
    assert result.exit_code == 2 and "--setting" in result.output
