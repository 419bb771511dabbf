"""One policy for bad frames in every command: stop at the first, naming its file, or with
``--skip-bad`` go on, count the skipped frames in the summary and list them in skipped.csv.
Warnings from worker processes print as ``warning: <file>: ...`` lines."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flic_cli.cli import main


@pytest.fixture
def broken(small_sample, tmp_path: Path) -> tuple[Path, Path]:
    """Copies of the sample with frame 1 corrupt: (SemanticKITTI root, Moosmann log)."""
    kitti, log = tmp_path / "kitti", tmp_path / "log"
    shutil.copytree(small_sample.kitti_root, kitti)
    shutil.copytree(small_sample.moosmann_log, log)
    path = kitti / "sequences" / "00" / "velodyne" / "000001.bin"
    path.write_bytes(path.read_bytes()[:-5])
    next(log.rglob("scan00001.png")).write_bytes(b"broken")
    return kitti, log


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    captured = capsys.readouterr()
    return int(info.value.code or 0), captured.out, captured.err


COMMANDS = {
    "segment": lambda k, log, out: ["segment", k, "--out", out],
    "segment-jobs": lambda k, log, out: ["segment", k, "--out", out, "--jobs", "2"],
    "evaluate": lambda k, log, out: ["evaluate", k, "--methods", "flic0", "--out", out],
    "sweep": lambda k, log, out: [
        "sweep-threshold",
        k,
        "--from",
        "0.8",
        "--to",
        "0.8",
        "--out",
        out,
    ],
    "benchmark": lambda k, log, out: ["benchmark", log, "--methods", "flic0", "--out", out],
}


@pytest.mark.slow
@pytest.mark.parametrize("command", COMMANDS)
def test_stop_or_skip(command, broken, tmp_path, capsys) -> None:
    kitti, log = broken
    bad = "scan00001.png" if command == "benchmark" else "000001.bin"
    argv = COMMANDS[command](kitti, log, tmp_path / "stop")
    code, out, err = _run(argv, capsys)
    assert code == 2
    assert bad in err and "Traceback" not in err
    assert not (tmp_path / "stop" / "skipped.csv").exists()

    argv = COMMANDS[command](kitti, log, tmp_path / "skip")
    code, out, err = _run([*argv, "--skip-bad"], capsys)
    assert code == 0, err
    assert f"{bad}" in err and "--skip-bad" in err
    skipped = pd.read_csv(tmp_path / "skip" / "skipped.csv", dtype={"sequence": str})
    assert skipped["frame"].tolist() == [1] and skipped["file"].str.endswith(bad).all()
    assert "skipped 1 bad frame" in out + err


@pytest.mark.slow
def test_worker_warnings_are_one_line_each(small_sample, tmp_path, capsys) -> None:
    kitti = tmp_path / "kitti"
    shutil.copytree(small_sample.kitti_root, kitti)
    for frame in (0, 2):
        path = kitti / "sequences" / "00" / "velodyne" / f"{frame:06d}.bin"
        raw = np.fromfile(path, dtype="<f4").reshape(-1, 4)
        raw[::50, 1] = np.nan
        raw.tofile(path)
    argv = ["evaluate", kitti, "--methods", "flic0", "--jobs", "2", "--out", tmp_path / "o"]
    code, out, err = _run(argv, capsys)
    assert code == 0, err
    lines = [ln for ln in err.splitlines() if "NaN" in ln]
    assert len(lines) == 2, err
    for frame, line in zip((0, 2), sorted(lines), strict=True):
        assert line.startswith(f"warning: {kitti}/sequences/00/velodyne/{frame:06d}.bin: dropped")
    assert "UserWarning" not in err and "warnings.warn" not in err
