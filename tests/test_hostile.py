"""Issue 24: the 18 defects a hostile user found, each reproduced on data made here.

End-to-end cases go through the installed entry point (:func:`flic_cli.cli.main`, or ``python -m
flic_cli`` in a subprocess where a signal, a resource limit or a hang is involved) and check what
README promises for bad input: exit code 2, exactly one stderr line ``error: <file>: <problem>``,
no traceback, nothing half-written or left behind.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from flic_cli.cli import main
from flic_cli.errors import FlicInputError

# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def _run(argv: list[object], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """``flic ARGV`` in this process: (exit code, stdout, stderr)."""
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    captured = capsys.readouterr()
    code = info.value.code
    return (0 if code is None else int(code)), captured.out, captured.err


def _cli(argv: list[object], timeout: float = 300, **kwargs) -> subprocess.CompletedProcess:
    """``flic ARGV`` in a subprocess (the installed entry point's code path)."""
    code = "import sys; from flic_cli.cli import main; main(sys.argv[1:])"
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kwargs,
    )


def _one_error(code: int, out: str, err: str, *names: object) -> str:
    """Exit 2, one ``error:`` line naming ``names``, no traceback; the error line."""
    assert code == 2, (out, err)
    errors = [ln for ln in err.splitlines() if ln.startswith("error: ")]
    assert len(errors) == 1, err
    assert "Traceback" not in out + err, err
    for name in names:
        assert str(name) in errors[0], errors[0]
    return errors[0]


def _leftovers(folder: Path) -> list[Path]:
    """Temporary files and staging folders of flic's writers under ``folder``."""
    return [*folder.rglob(".*staging-*"), *folder.rglob(".*.tmp-*")]


class Data:
    """A copy of the 3-frame sample: a SemanticKITTI root and a Moosmann log."""

    def __init__(self, sample, tmp: Path) -> None:
        self.tmp = tmp
        self.kitti = tmp / "kitti"
        self.log = tmp / "log"
        shutil.copytree(sample.kitti_root, self.kitti)
        shutil.copytree(sample.moosmann_log, self.log)
        self.out = tmp / "results" / "out"

    @property
    def velodyne(self) -> Path:
        return self.kitti / "sequences" / "00" / "velodyne"

    def bin(self, frame: int) -> Path:
        return self.velodyne / f"{frame:06d}.bin"

    @property
    def cfg(self) -> Path:
        return next(self.log.rglob("img.cfg"))

    def pngs(self) -> list[Path]:
        return sorted(self.log.rglob("scan*.png"))

    def set_cfg_field(self, index: int, value: str) -> None:
        """Replace the ``index``-th ``;`` field of img.cfg's data."""
        lines = self.cfg.read_text().splitlines()
        k = next(i for i, ln in enumerate(lines) if not ln.lstrip().startswith("#"))
        fields = lines[k].split(";")
        fields[index] = value
        lines[k] = ";".join(fields)
        self.cfg.write_text("\n".join(lines) + "\n")


@pytest.fixture
def data(small_sample, tmp_path: Path) -> Data:
    return Data(small_sample, tmp_path)


@pytest.fixture(scope="module")
def finished_run(small_sample, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list]:
    """An evaluate run of flic0 on frames 0:2 (no-ground setting), and its argv."""
    out = tmp_path_factory.mktemp("run") / "out"
    argv = ["evaluate", small_sample.kitti_root, "--methods", "flic0", "--frames", "0:2"]
    argv += ["--setting", "no-ground", "--out", out]
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    assert info.value.code in (0, None)
    return out, argv


def _copy_run(finished_run: tuple[Path, list], tmp_path: Path) -> tuple[Path, list]:
    out, argv = finished_run
    copy = tmp_path / "run"
    shutil.copytree(out, copy)
    return copy, [*argv[:-1], copy]


# ---------------------------------------------------------------------------------------------
# 1 and 9: img.cfg with non-finite numbers
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("index", "value"),
    [(0, "inf"), (1, "nan"), (1, "-inf"), (4, "nan"), (-2, "inf")],
    ids=["width-inf", "height-nan", "height-minus-inf", "pitch-nan", "last-pitch-inf"],
)
def test_img_cfg_non_finite_numbers_are_refused(data: Data, index, value, capsys) -> None:
    """1: a non-finite size was an OverflowError / ValueError traceback; 9: a non-finite pitch
    was taken (numpy warnings, exit 0, output from garbage)."""
    data.set_cfg_field(index, value)
    code, out, err = _run(["segment", data.log, "--out", data.out], capsys)
    line = _one_error(code, out, err, data.cfg, "not a finite number")
    assert value in line
    assert not data.out.exists() and not _leftovers(data.tmp)


# ---------------------------------------------------------------------------------------------
# 2: sweep-threshold with non-finite bounds
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("option", "value"),
    [("--from", "nan"), ("--to", "nan"), ("--step", "nan"), ("--to", "inf")],
)
def test_sweep_non_finite_bounds_are_refused(data: Data, option, value, capsys) -> None:
    argv = ["sweep-threshold", data.kitti, "--from", "0.2", "--to", "1", "--step", "0.1"]
    argv[argv.index(option) + 1] = value
    code, out, err = _run([*argv, "--out", data.out], capsys)
    _one_error(code, out, err, option, "finite")
    assert not data.out.exists()


# ---------------------------------------------------------------------------------------------
# 3, 4, 11: the resumable store
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("content", ["[1]\n", '"run"\n', "3\n", "null\n"])
def test_run_json_that_is_not_an_object(finished_run, tmp_path, content, capsys) -> None:
    """3: JSON that is not an object was an AttributeError traceback."""
    out, argv = _copy_run(finished_run, tmp_path)
    (out / "run.json").write_text(content)
    before = sorted(p.name for p in (out / "parts" / "00").iterdir())
    code, stdout, err = _run([*argv, "--resume"], capsys)
    _one_error(code, stdout, err, out / "parts", "no valid run.json")
    assert sorted(p.name for p in (out / "parts" / "00").iterdir()) == before


def _append_bad_byte(path: Path) -> None:
    with open(path, "ab") as f:
        f.write(b"\xff\n")


def _cut(path: Path) -> None:
    path.write_bytes(path.read_bytes()[:-7])


def _extra_field(path: Path) -> None:
    path.write_text(path.read_text() + "a,b,c\n")


def _bad_value(path: Path) -> None:
    lines = path.read_text().splitlines()
    fields = lines[1].split(",")
    fields[-1] = "many"  # a number column
    path.write_text("\n".join([lines[0], ",".join(fields), *lines[2:]]) + "\n")


@pytest.mark.slow
@pytest.mark.parametrize(
    "damage", [_append_bad_byte, _cut, _extra_field, _bad_value], ids=lambda f: f.__name__
)
def test_corrupt_part_file_is_named(finished_run, tmp_path, damage, capsys) -> None:
    """4: a part that is not UTF-8 was a UnicodeDecodeError, a truncated one a ParserError."""
    out, argv = _copy_run(finished_run, tmp_path)
    part = out / "parts" / "00" / "000001.frames.csv"
    damage(part)
    code, stdout, err = _run([*argv, "--resume"], capsys)
    _one_error(code, stdout, err, part, "corrupt", "--resume")
    # what the message says gets out of it: delete the part, --resume computes its frame again
    part.unlink()
    code, stdout, err = _run([*argv, "--resume"], capsys)
    assert code == 0, err
    assert part.is_file()


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["objects", "frames", "ground"])
def test_deleted_part_file_is_computed_again(finished_run, tmp_path, kind, capsys) -> None:
    """11: a deleted part made --resume say "rerun with --resume" forever."""
    out, argv = _copy_run(finished_run, tmp_path)
    parts = out / "parts" / "00"
    reference = {p.name: p.read_text() for p in parts.glob("*.objects.csv")}
    (parts / f"000001.{kind}.csv").unlink()
    code, stdout, err = _run([*argv, "--resume"], capsys)
    assert code == 0, err
    assert "1 finished earlier" in err  # frame 0 kept, frame 1 computed again
    assert (parts / f"000001.{kind}.csv").is_file()
    assert {p.name: p.read_text() for p in parts.glob("*.objects.csv")} == reference
    original = pd.read_csv(finished_run[0] / "table.csv")
    pd.testing.assert_frame_equal(pd.read_csv(out / "table.csv"), original)


# ---------------------------------------------------------------------------------------------
# 5: every frame bad with --skip-bad
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("command", ["evaluate", "sweep-threshold"])
def test_skip_bad_with_every_frame_bad(data: Data, command, capsys) -> None:
    """5: evaluate ended in a matplotlib traceback; skipped.csv was not written."""
    for k in range(3):
        data.bin(k).write_bytes(data.bin(k).read_bytes()[:-5])
    argv = [command, data.kitti, "--skip-bad", "--out", data.out]
    argv += ["--methods", "flic0"] if command == "evaluate" else ["--method", "flic0"]
    code, out, err = _run(argv, capsys)
    _one_error(code, out, err, data.kitti, "every selected frame is bad", "skipped.csv")
    skipped = pd.read_csv(data.out / "skipped.csv")
    assert skipped["frame"].tolist() == [0, 1, 2]
    assert all("not a multiple of 16" in r for r in skipped["reason"])
    assert not (data.out / "table.csv").exists() and not (data.out / "sweep.csv").exists()
    assert not _leftovers(data.tmp)


# ---------------------------------------------------------------------------------------------
# 6: disk full
# ---------------------------------------------------------------------------------------------


def test_atomic_write_on_a_full_disk_is_one_line(tmp_path: Path) -> None:
    from flic_cli.io.atomic import atomic_write

    target = tmp_path / "table.csv"
    with pytest.raises(FlicInputError, match="No space left on device") as info:
        with atomic_write(target) as tmp:
            tmp.write_text("half")
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    assert info.value.path == target
    assert list(tmp_path.iterdir()) == []  # the temporary file is gone, nothing half-written


def _file_size_limit(limit: int):
    """A ``preexec_fn``: files may not grow beyond ``limit`` bytes (a write beyond it fails with
    EFBIG, as a full disk fails with ENOSPC)."""

    def limit_files() -> None:
        import resource

        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return limit_files


@pytest.mark.slow
@pytest.mark.parametrize(
    "argv",
    [
        ["segment", "{kitti}", "--method", "flic0", "--export", "ply"],
        ["evaluate", "{kitti}", "--methods", "flic0", "--setting", "no-ground"],
        ["benchmark", "{kitti}", "--methods", "flic0", "--warmup", "0", "--repeat", "1"],
    ],
    ids=["segment-ply", "evaluate", "benchmark"],
)
def test_output_that_cannot_be_written_for_lack_of_space(data: Data, argv) -> None:
    """6: a full disk ended in ``OSError: [Errno 28]`` tracebacks. Files here may not grow
    beyond 20 kB (RLIMIT_FSIZE, no root needed): the first large output fails."""
    argv = [a.format(kitti=data.kitti) for a in argv] + ["--out", data.out]
    run = _cli(argv, preexec_fn=_file_size_limit(20_000))
    line = _one_error(run.returncode, run.stdout, run.stderr, "cannot be written")
    assert str(data.out) in line
    assert not _leftovers(data.tmp)
    for path in data.out.rglob("*") if data.out.exists() else []:
        assert not path.is_file() or path.stat().st_size < 20_000  # no cut-off file
    if argv[0] == "evaluate":  # the finished frames are kept: --resume completes the run
        again = _cli([*argv, "--resume"])
        assert again.returncode == 0, again.stderr
        assert (data.out / "table.csv").is_file()


# ---------------------------------------------------------------------------------------------
# 7: the dask scheduler's address
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("command", ["evaluate", "sweep-threshold"])
@pytest.mark.parametrize("address", ["not a url", "tcp://host", "tcp://host:99999", "::"])
def test_malformed_scheduler_address_is_refused_at_once(data, command, address, capsys) -> None:
    """7: the error came, then 40 s later a ``Client.__del__`` traceback."""
    start = time.perf_counter()
    code, out, err = _run([command, data.kitti, "--scheduler", address, "--out", data.out], capsys)
    line = _one_error(code, out, err, "--scheduler", repr(address))
    assert "--skip-bad" not in line
    assert time.perf_counter() - start < 60  # no connection attempt (it would wait 20 s)
    assert not data.out.exists()


@pytest.mark.slow
@pytest.mark.parametrize("command", ["evaluate", "sweep-threshold"])
def test_unreachable_scheduler_gets_no_skip_bad_hint(data: Data, command) -> None:
    pytest.importorskip("distributed")
    seq = data.velodyne.parent
    shutil.copy(data.bin(2), data.bin(3))  # a 4th frame: evaluate runs 3 here, then the cluster
    shutil.copy(seq / "labels" / "000002.label", seq / "labels" / "000003.label")
    method = ["--methods", "flic0"] if command == "evaluate" else ["--method", "flic0"]
    run = _cli(
        [command, data.kitti, *method, "--scheduler", "tcp://127.0.0.1:9", "--out", data.out]
    )
    line = _one_error(run.returncode, run.stdout, run.stderr, "cannot reach the dask scheduler")
    assert "--skip-bad" not in line


# ---------------------------------------------------------------------------------------------
# 8: memory of methods that grows with density (DBSCAN)
# ---------------------------------------------------------------------------------------------


def test_neighbour_pair_bound_is_an_upper_bound() -> None:
    from flic_cli.methods.dbscan import neighbour_pairs_bound

    rng = np.random.default_rng(7)
    for eps in (0.05, 0.3, 1.0):
        xyz = np.r_[rng.uniform(-3, 3, (400, 3)), np.full((50, 3), 1.0)]  # spread + coinciding
        d = np.linalg.norm(xyz[:, None] - xyz[None], axis=-1)
        exact = int((d <= eps).sum())  # brute force, self pairs included
        bound = neighbour_pairs_bound(xyz, eps)
        assert exact <= bound <= 30 * exact


def test_dbscan_on_coinciding_points_stays_within_the_budget(monkeypatch) -> None:
    """8: coinciding points took all memory. Over a (small) budget they are merged into one
    weighted point: the same DBSCAN, in bounded memory."""
    from flic_cli.methods import dbscan

    rng = np.random.default_rng(3)
    xyz = np.r_[np.full((3000, 3), (5.0, 5.0, 0.0)), rng.uniform(20, 40, (200, 3))]
    direct = dbscan.dbscan_labels(xyz, 0.5, 5, 100)
    monkeypatch.setattr(dbscan, "MAX_NEIGHBOUR_PAIRS", 10_000)  # 3000^2 pairs are far beyond
    fitted: list[int] = []
    real_fit = __import__("sklearn.cluster", fromlist=["DBSCAN"]).DBSCAN.fit

    def spy(self, X, y=None, sample_weight=None):
        fitted.append(len(X))
        return real_fit(self, X, y, sample_weight)

    monkeypatch.setattr("sklearn.cluster.DBSCAN.fit", spy)
    labels = dbscan.dbscan_labels(xyz, 0.5, 5, 100)
    assert fitted == [201]  # one point for the 3000 copies
    np.testing.assert_array_equal(labels, direct)
    assert (labels[:3000] == 1).all() and (labels[3000:] == 0).all()


def test_dbscan_too_dense_even_merged_is_refused(monkeypatch) -> None:
    from flic_cli.methods import dbscan

    xyz = np.full((2000, 3), 5.0) + np.random.default_rng(1).normal(0, 1e-3, (2000, 3))
    monkeypatch.setattr(dbscan, "MAX_NEIGHBOUR_PAIRS", 10_000)
    with pytest.raises(FlicInputError, match="too densely .* beyond the budget"):
        dbscan.dbscan_labels(xyz, 0.5, 5, 100)


def _dense_frame(data: Data, frame: int, jitter: float) -> None:
    scan = np.fromfile(data.bin(frame), dtype="<f4").reshape(-1, 4)
    rng = np.random.default_rng(0)
    scan[:, :3] = np.array([5.0, 5.0, 0.0], np.float32) + rng.normal(0, jitter, (len(scan), 3))
    scan.astype("<f4").tofile(data.bin(frame))


@pytest.mark.slow
def test_dbscan_on_a_scan_of_coinciding_points(data: Data, monkeypatch, capsys) -> None:
    """The issue's case (``a[:, :3] = (5, 5, 0)``): segmented, in bounded memory."""
    from flic_cli.methods import dbscan

    monkeypatch.setattr(dbscan, "MAX_NEIGHBOUR_PAIRS", 100_000)
    _dense_frame(data, 1, 0.0)
    argv = ["segment", data.kitti, "--method", "dbscan", "--frames", "1", "--setting"]
    code, out, err = _run([*argv, "no-ground", "--out", data.out], capsys)
    assert code == 0, err
    pred = np.fromfile(data.out / "sequences/00/predictions/000001.label", dtype="<u4")
    assert len(np.unique(pred[pred > 0] >> 16)) <= 1  # at most one cluster: one place


@pytest.mark.slow
def test_dbscan_on_a_too_dense_scan_names_the_frame(data: Data, monkeypatch, capsys) -> None:
    from flic_cli.methods import dbscan

    monkeypatch.setattr(dbscan, "MAX_NEIGHBOUR_PAIRS", 100_000)
    _dense_frame(data, 1, 1e-3)
    argv = ["segment", data.kitti, "--method", "dbscan", "--frames", "1", "--setting"]
    code, out, err = _run([*argv, "no-ground", "--out", data.out], capsys)
    _one_error(code, out, err, data.bin(1), "too densely")
    assert not data.out.exists() and not _leftovers(data.tmp)


# ---------------------------------------------------------------------------------------------
# 10: a lock on --out
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("command", ["evaluate", "segment", "sweep-threshold", "benchmark"])
def test_out_in_use_by_another_run_is_refused(data: Data, command, capsys) -> None:
    """10: two runs into one --out mixed their tables."""
    from flic_cli.io.atomic import locked_folder

    data.out.mkdir(parents=True)
    (data.out / "table.csv").write_text("of the other run\n")
    with locked_folder(data.out):  # the other run, still going
        code, out, err = _run([command, data.kitti, "--out", data.out], capsys)
    _one_error(code, out, err, data.out, "another flic run")
    assert [p.name for p in data.out.iterdir()] == ["table.csv"]
    assert (data.out / "table.csv").read_text() == "of the other run\n"


@pytest.mark.slow
def test_lock_is_released_when_its_holder_is_killed(tmp_path: Path) -> None:
    from flic_cli.io.atomic import locked_folder

    out = tmp_path / "out"
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from flic_cli.io.atomic import locked_folder\n"
            f"with locked_folder({str(out)!r}):\n    print('held', flush=True); time.sleep(600)",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "held"
        with pytest.raises(FlicInputError, match="another flic run"):
            with locked_folder(out):
                pass
    finally:
        holder.kill()  # SIGKILL: no clean-up code runs; the kernel drops the lock
        holder.wait()
    with locked_folder(out) as held:
        assert held == out
    assert out.is_dir()  # made by the killed holder, not by this run: kept
    shutil.rmtree(out)
    with locked_folder(out / "nested"):
        assert (out / "nested").is_dir()
    assert not out.exists()  # made for this lock and left empty: removed, parents included


# ---------------------------------------------------------------------------------------------
# 12: staging folders of a killed segment run
# ---------------------------------------------------------------------------------------------

_KILL_AFTER_FIRST_FRAME = """
import os, signal, sys
from flic_cli.io.semantickitti import SemanticKittiDataset
write = SemanticKittiDataset.write_prediction
def write_then_terminate(*args, **kwargs):
    path = write(*args, **kwargs)
    os.kill(os.getpid(), signal.SIGTERM)  # as `kill PID` does, mid-run
    return path
SemanticKittiDataset.write_prediction = staticmethod(write_then_terminate)
from flic_cli.cli import main
main(sys.argv[1:])
"""


@pytest.mark.slow
def test_segment_killed_by_sigterm_leaves_no_staging(data: Data) -> None:
    argv = ["segment", data.kitti, "--method", "flic0", "--out", data.out]
    run = subprocess.run(
        [sys.executable, "-c", _KILL_AFTER_FIRST_FRAME, *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 130, run.stderr
    assert "interrupted" in run.stderr and "Traceback" not in run.stderr
    assert not _leftovers(data.tmp)
    assert not data.out.exists()  # nothing half-written: no prediction of the stopped run


@pytest.mark.slow
def test_later_run_clears_what_a_killed_run_left(data: Data, capsys) -> None:
    """A SIGKILLed run cannot clean up: the next run into the same --out does, and touches no
    other names."""
    parent = data.out.parent
    parent.mkdir(parents=True)
    stale = parent / ".out.staging-k1ll3d_0"
    (stale / "sequences/00/predictions").mkdir(parents=True)
    (stale / "sequences/00/predictions/000000.label").write_bytes(b"partial")
    kept = [parent / ".other.staging-abcdefgh", parent / ".out.staging-notmine", parent / "x"]
    for path in kept:
        path.mkdir()
    code, out, err = _run(["segment", data.kitti, "--method", "flic0", "--out", data.out], capsys)
    assert code == 0, err
    assert not stale.exists()
    assert all(p.is_dir() for p in kept)
    assert len(list((data.out / "sequences/00/predictions").glob("*.label"))) == 3


# ---------------------------------------------------------------------------------------------
# 13: scans in a log folder and in its range/ subfolder
# ---------------------------------------------------------------------------------------------


def test_scans_in_log_and_range_folder_are_refused(data: Data, capsys) -> None:
    """13: the scans in range/ were skipped without a word."""
    scans = data.pngs()
    log = scans[0].parent
    (log / "range").mkdir()
    shutil.copy(scans[0], log / "range" / "scan00007.png")
    code, out, err = _run(["segment", data.log, "--out", data.out], capsys)
    _one_error(code, out, err, log, "both directly and in range/")
    assert not data.out.exists()


# ---------------------------------------------------------------------------------------------
# 14: a config path that is a folder
# ---------------------------------------------------------------------------------------------


def test_config_path_that_is_a_folder(data: Data, capsys) -> None:
    folder = data.tmp / "configs"
    folder.mkdir()
    code, out, err = _run(["evaluate", data.kitti, "--config", folder, "--out", data.out], capsys)
    line = _one_error(code, out, err, folder, "is a folder, expected a TOML config file")
    assert "does not exist" not in line


# ---------------------------------------------------------------------------------------------
# 15: evaluate stopped by a bad frame prints one line
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_evaluate_stopped_by_a_bad_frame_prints_only_the_error(data: Data, capsys) -> None:
    data.bin(1).write_bytes(data.bin(1).read_bytes()[:-3])
    argv = ["evaluate", data.kitti, "--methods", "flic0", "--out", data.out]
    code, out, err = _run(argv, capsys)
    _one_error(code, out, err, data.bin(1))
    # besides the progress bar (tqdm's carriage-return updates) and, on a fresh install, the
    # note that the kernels compile, only the error line
    lines = [ln.split("\r")[-1] for ln in err.splitlines()]
    shown = [ln for ln in lines if ln.strip() and not ln.startswith(("evaluate", "note: first"))]
    assert shown == [next(ln for ln in lines if ln.startswith("error: "))]


# ---------------------------------------------------------------------------------------------
# 16: frame names that are not plain frame numbers
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["00000\u00b2.bin", "\u0660\u0660\u0660\u0660\u0660\u0661.bin"])
def test_bin_names_in_other_digits_are_left_out(data: Data, name, capsys) -> None:
    """16: ``"00000²".isdigit()`` is true but ``int()`` fails: the listing crashed; Arabic-Indic
    digits made a second frame 1."""
    shutil.copy(data.bin(1), data.velodyne / name)
    code, out, err = _run(["segment", data.kitti, "--method", "flic0", "--out", data.out], capsys)
    assert code == 0, err
    assert f"warning: {data.velodyne / name}: left out" in err
    assert "segmented 3 frames" in out
    predictions = sorted(p.name for p in (data.out / "sequences/00/predictions").iterdir())
    assert predictions == ["000000.label", "000001.label", "000002.label"]


def test_two_bin_names_for_one_frame_are_refused(data: Data, capsys) -> None:
    """16: ``0000001.bin`` and ``000001.bin`` were frame 1 twice, one prediction overwritten."""
    twin = data.velodyne / "0000001.bin"
    shutil.copy(data.bin(2), twin)
    code, out, err = _run(["segment", data.kitti, "--out", data.out], capsys)
    _one_error(code, out, err, "names frame 1", "000001.bin")
    assert not data.out.exists()


def test_png_names_for_one_frame_or_in_other_digits(data: Data, capsys) -> None:
    from flic_cli.io import open_dataset

    first = data.pngs()[0]
    other = first.with_name("scan\u0661\u0662.png")  # Arabic-Indic 12
    shutil.copy(first, other)
    with pytest.warns(UserWarning, match="left out: frame numbers are written in the digits"):
        refs = open_dataset(data.log).refs()
    assert other not in [r.path for r in refs] and len(refs) == 3
    shutil.copy(first, first.with_name("scan0.png"))  # frame 0 again
    code, out, err = _run(["segment", data.log, "--out", data.out], capsys)
    _one_error(code, out, err, "names frame 0", first.name)


# ---------------------------------------------------------------------------------------------
# 17: special files where a scan is expected
# ---------------------------------------------------------------------------------------------


@pytest.fixture
def alarm() -> Iterator[None]:
    """Fail a test that blocks for more than 60 s instead of hanging the suite."""

    def timeout(signum, frame):
        raise TimeoutError("blocked on a special file")

    old = signal.signal(signal.SIGALRM, timeout)
    signal.alarm(60)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def _fifo(path: Path) -> None:
    path.unlink()
    os.mkfifo(path)


def _zero_device(path: Path) -> None:
    path.unlink()
    path.symlink_to("/dev/zero")


@pytest.mark.parametrize("special", [_fifo, _zero_device], ids=["fifo", "dev-zero"])
def test_special_files_do_not_block(data: Data, special, alarm, capsys) -> None:
    from flic_cli.io.moosmann import read_img_cfg, read_png_range
    from flic_cli.io.semantickitti import read_bin

    special(data.bin(1))
    with pytest.raises(FlicInputError, match="not a regular file"):
        read_bin(data.bin(1))
    png = data.pngs()[1]
    special(png)
    with pytest.raises(FlicInputError, match="not a regular file"):
        read_png_range(png, read_img_cfg(data.cfg))
    code, out, err = _run(["segment", data.kitti, "--out", data.out], capsys)
    _one_error(code, out, err, data.bin(1), "not a regular file")
    code, out, err = _run(["segment", data.log, "--out", data.out], capsys)
    _one_error(code, out, err, png, "not a regular file")
    assert not data.out.exists()


def test_config_fifo_does_not_block(data: Data, alarm, capsys) -> None:
    fifo = data.tmp / "my.toml"
    os.mkfifo(fifo)
    code, out, err = _run(["evaluate", data.kitti, "--config", fifo, "--out", data.out], capsys)
    _one_error(code, out, err, fifo, "not a regular file")


# ---------------------------------------------------------------------------------------------
# 18: --jobs far beyond the frames or cores
# ---------------------------------------------------------------------------------------------


def test_jobs_are_clamped_to_frames_and_cores() -> None:
    from flic_cli.runs.parallel import cpu_cores, jobs_note, resolve_jobs

    cores = cpu_cores()
    assert resolve_jobs(500, 2) == min(2, cores)
    assert resolve_jobs(500) == cores
    assert resolve_jobs(0, 1000) == cores and resolve_jobs(-1, 1) == 1
    assert resolve_jobs(1, 0) == 1
    assert jobs_note(1, 10) is None and jobs_note(0, 10) is None
    note = jobs_note(500, 2)
    assert note is not None and note.startswith("note: --jobs 500: using")
    assert f"{min(2, cores)} process(es) (2 frame(s), {cores} CPU core(s))" in note


@pytest.mark.slow
def test_many_jobs_on_few_frames(data: Data) -> None:
    """18: --jobs 300 on 3 frames started 300 processes: minutes of start-up, hundreds of
    leaked-semaphore warnings."""
    run = _cli(["segment", data.kitti, "--method", "flic0", "--jobs", 300, "--out", data.out])
    assert run.returncode == 0, run.stderr
    assert "note: --jobs 300: using" in run.stderr
    assert "leaked" not in run.stderr and "Traceback" not in run.stderr
    assert len(list((data.out / "sequences/00/predictions").glob("*.label"))) == 3


# ---------------------------------------------------------------------------------------------
# Also: first-run compilation note and an honest ETA; unique one-point instance ids
# ---------------------------------------------------------------------------------------------


def test_first_run_says_the_kernels_compile(tmp_path, monkeypatch, capsys) -> None:
    from flic_cli.io.base import FrameRef
    from flic_cli.runs import frames

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))  # an empty cache: a fresh install
    assert not frames.kernels_cached()
    refs = [FrameRef("00", k, tmp_path / f"{k}.bin", None, "semantickitti") for k in range(2)]
    assert [r.frame for r, _ in frames.FrameLoop(_frame_number, refs)] == [0, 1]
    assert frames.COMPILE_NOTE in capsys.readouterr().err
    (tmp_path / "x.nbi").write_bytes(b"")  # numba's index of a cached kernel
    assert frames.kernels_cached()
    list(frames.FrameLoop(_frame_number, refs))
    assert frames.COMPILE_NOTE not in capsys.readouterr().err


def _frame_number(ref) -> int:
    return ref.frame


def test_eta_leaves_out_the_first_frame() -> None:
    """The first frame (98 s of compilation on a fresh install) made the ETA 31 min."""
    from tqdm import tqdm

    from flic_cli.runs.frames import _restart_rate

    with tqdm(total=100, disable=False, file=open(os.devnull, "w")) as bar:  # noqa: SIM115
        bar.start_t -= 98.0  # the first frame took 98 s
        bar.update(1)
        assert bar.format_dict["elapsed"] >= 98.0
        _restart_rate(bar)
        d = bar.format_dict
        assert d["n"] == 1 and d["initial"] == 1 and d["elapsed"] < 5.0
        time.sleep(0.05)
        bar.update(1)
        rate = bar.format_dict["rate"] or (bar.n - bar.initial) / bar.format_dict["elapsed"]
        assert 1.0 / rate < 5.0  # seconds per frame from the second frame on, not 98


def test_one_point_instances_are_unique_across_classes() -> None:
    from flic_cli.semantics import combine

    car, bicyclist, moving_car, person = 10, 31, 252, 30
    sem = np.array([car, moving_car, car, bicyclist, person, moving_car, 40])
    ids = np.array([0, 0, 3, 0, 0, 0, 0])
    inst = combine(sem, ids) >> 16
    loose = inst[[0, 1, 3, 4, 5]]
    assert len(set(loose.tolist())) == 5 and loose.min() > 3  # above the cluster, one each
    assert inst[2] == 3 and inst[6] == 0
