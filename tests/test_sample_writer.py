"""Writing the sample: bad input gives one-line errors before anything is written, a failure
leaves nothing behind, a previous sample is replaced, and the files go through flic_cli.io."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest
from oracles import file_tree
from typer.testing import CliRunner

from flic_cli.cli import app
from flic_cli.errors import FlicInputError
from flic_cli.io import read_calib, read_img_cfg, read_poses, write_calib, write_poses, write_times
from flic_cli.sample import HDL64_PITCH_DEG, make_scene, write_sample
from flic_cli.sample import writer as sample_writer

runner = CliRunner()


def entries(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# ---------------------------------------------------------------------------------------------
# Bad input: one line, before anything is written
# ---------------------------------------------------------------------------------------------


def _file(tmp: Path) -> Path:
    (tmp / "out").write_text("mine\n")
    return tmp / "out"


def _foreign(tmp: Path) -> Path:
    (tmp / "out").mkdir()
    (tmp / "out" / "notes.txt").write_text("mine\n")
    return tmp / "out"


def _sample_plus_foreign(tmp: Path) -> Path:
    write_sample(tmp / "out", frames=1)
    (tmp / "out" / "semantickitti" / "sequences" / "00" / "predictions").mkdir()
    (
        tmp / "out" / "semantickitti" / "sequences" / "00" / "predictions" / "000000.label"
    ).write_bytes(b"\0" * 4)
    return tmp / "out"


def _under_file(tmp: Path) -> Path:
    (tmp / "afile").write_text("mine\n")
    return tmp / "afile" / "out"


BAD = [
    # (id, make OUT, kwargs, words the one-line message must hold)
    ("frames-0", lambda t: t / "out", {"frames": 0}, ["--frames 0", "at least 1"]),
    ("frames-neg", lambda t: t / "out", {"frames": -5}, ["--frames -5", "at least 1"]),
    ("seed-neg", lambda t: t / "out", {"seed": -1}, ["--seed -1", ">= 0"]),
    ("width-0", lambda t: t / "out", {"kitti_width": 0}, ["kitti_width 0"]),
    ("out-is-file", _file, {}, ["out", "is a file"]),
    ("out-foreign", _foreign, {}, ["out", "other files than a flic sample"]),
    ("out-sample-plus", _sample_plus_foreign, {}, ["out", "other files than a flic sample"]),
    ("parent-is-file", _under_file, {}, ["afile/out", "parent is a file"]),
]


@pytest.mark.parametrize(("make", "kwargs", "words"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, make, kwargs, words) -> None:
    out = make(tmp_path)
    before = file_tree(tmp_path)
    names = entries(tmp_path)
    with pytest.raises(FlicInputError) as err:
        write_sample(out, frames=kwargs.pop("frames", 2), **kwargs)
    message = str(err.value)
    assert "\n" not in message
    for word in words:
        assert word in message
    assert entries(tmp_path) == names and file_tree(tmp_path) == before


@pytest.mark.parametrize(
    ("args", "make", "words"),
    [
        (["--frames", "-5"], lambda t: t / "out", ["--frames -5"]),
        (["--frames", "0"], lambda t: t / "out", ["--frames 0"]),
        (["--seed", "-3"], lambda t: t / "out", ["--seed -3"]),
        ([], _file, ["is a file"]),
        ([], _foreign, ["other files than a flic sample"]),
        ([], _under_file, ["parent is a file"]),
    ],
    ids=["frames-neg", "frames-0", "seed-neg", "out-is-file", "out-foreign", "parent-is-file"],
)
def test_flic_sample_bad_input_exits_2_with_one_line(tmp_path, args, make, words) -> None:
    out = make(tmp_path)
    before = file_tree(tmp_path)
    result = runner.invoke(app, ["sample", str(out), "--frames", "1", *args])
    assert result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert all(word in lines[0] for word in words)
    assert "Traceback" not in result.output
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert file_tree(tmp_path) == before
    assert not [p for p in tmp_path.iterdir() if ".tmp-" in p.name]


@pytest.mark.slow
def test_flic_sample_writes_a_sample(tmp_path) -> None:
    result = runner.invoke(app, ["sample", str(tmp_path / "s"), "--frames", "1"])
    assert result.exit_code == 0, result.output
    assert "wrote 1 frames" in result.output
    assert entries(tmp_path / "s") == ["moosmann", "semantickitti"]


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_unwritable_folder(tmp_path) -> None:
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        with pytest.raises(FlicInputError, match="is not writable"):
            write_sample(ro / "out", frames=1)
        assert entries(ro) == []
    finally:
        ro.chmod(0o755)


def test_unwritable_folder_reported_as_one_line(tmp_path, monkeypatch) -> None:
    """Whoever runs the tests (root too): a folder where no new folder can be made."""

    def refuse(self, mode=0o777, parents=False, exist_ok=False):
        if exist_ok and self.is_dir():
            return
        raise PermissionError(errno.EACCES, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", refuse)
    with pytest.raises(FlicInputError) as err:
        write_sample(tmp_path / "out", frames=1)
    assert "is not writable" in str(err.value) and str(tmp_path) in str(err.value)
    monkeypatch.undo()
    assert entries(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# Nothing half-written
# ---------------------------------------------------------------------------------------------


def _fail_on_second_png(monkeypatch, exc: BaseException) -> None:
    real = sample_writer.write_png_range
    calls = []

    def flaky(path, ranges):
        calls.append(path)
        if len(calls) == 2:
            raise exc
        real(path, ranges)

    monkeypatch.setattr(sample_writer, "write_png_range", flaky)


@pytest.mark.slow
@pytest.mark.parametrize(
    "exc",
    [OSError(errno.ENOSPC, "No space left on device"), KeyboardInterrupt()],
    ids=["disk-full", "ctrl-c"],
)
def test_a_failure_midway_leaves_nothing(tmp_path, monkeypatch, exc) -> None:
    _fail_on_second_png(monkeypatch, exc)
    out = tmp_path / "deep" / "er" / "out"
    expected = FlicInputError if isinstance(exc, OSError) else KeyboardInterrupt
    with pytest.raises(expected) as err:
        write_sample(out, frames=3)
    if expected is FlicInputError:
        assert "No space left on device" in str(err.value) and "\n" not in str(err.value)
    # Not even the parent folders created for it are left.
    assert entries(tmp_path) == []


@pytest.mark.slow
def test_a_failure_midway_keeps_the_previous_sample(tmp_path, monkeypatch) -> None:
    out = tmp_path / "out"
    write_sample(out, frames=2)
    before = file_tree(out)
    _fail_on_second_png(monkeypatch, OSError(errno.ENOSPC, "No space left on device"))
    with pytest.raises(FlicInputError):
        write_sample(out, frames=3, seed=1)
    assert file_tree(out) == before
    assert entries(tmp_path) == ["out"]


@pytest.mark.slow
def test_a_previous_sample_is_replaced_whole(tmp_path) -> None:
    out = tmp_path / "out"
    write_sample(out, frames=3)
    again = write_sample(out, frames=2, seed=1)
    seq = again.kitti_sequence
    assert entries(seq / "velodyne") == ["000000.bin", "000001.bin"]  # no stale frame 2
    assert entries(out / "moosmann") == ["img.cfg", "scan00000.png", "scan00001.png"]
    assert entries(tmp_path) == ["out"]
    fresh = write_sample(tmp_path / "fresh", frames=2, seed=1).kitti_root.parent
    assert file_tree(out) == file_tree(fresh)


@pytest.mark.slow
def test_an_empty_folder_is_used(tmp_path) -> None:
    out = tmp_path / "empty"
    out.mkdir()
    paths = write_sample(out, frames=1)
    assert paths.kitti_root == out / "semantickitti"
    assert entries(out) == ["moosmann", "semantickitti"]
    assert entries(tmp_path) == ["empty"]
    # The sample's folders get the permissions of the umask, not those of a private temp folder.
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o777 & ~umask


# ---------------------------------------------------------------------------------------------
# Written through flic_cli.io
# ---------------------------------------------------------------------------------------------


def test_text_files_read_back(small_sample) -> None:
    seq = small_sample.kitti_sequence
    poses = read_poses(seq / "poses.txt")
    assert poses.shape == (3, 3, 4)
    for k in range(3):
        np.testing.assert_allclose(poses[k], make_scene(0, k).pose, atol=1e-6)
    calib = read_calib(seq / "calib.txt")
    np.testing.assert_array_equal(calib["Tr"], np.eye(3, 4))
    assert calib["P2"][0, 3] == pytest.approx(45.38225)
    assert (seq / "times.txt").read_text() == "0.000000e+00\n1.000000e-01\n2.000000e-01\n"
    cfg = read_img_cfg(small_sample.moosmann_log / "img.cfg")
    assert (cfg.width, cfg.height, cfg.h_start_deg, cfg.h_stop_deg) == (870, 64, 180, -180)
    np.testing.assert_allclose(cfg.pitch_deg, HDL64_PITCH_DEG, atol=5e-5)
    text = (small_sample.moosmann_log / "img.cfg").read_text().splitlines()
    assert text[0].startswith("# synthetic HDL-64E street (flic sample)")
    assert text[1].startswith("870; 64; 180; -180; -1.9367; -1.6000; ")


def test_io_float_formats(tmp_path) -> None:
    """The writers' new format parameters: KITTI's own 6-digit style, and the default unchanged."""
    pose = np.array([[1.0, 0.0, 0.0, 12.3456789], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, -0.5]])
    write_poses(tmp_path / "p6.txt", pose[None], float_format=".6e")
    assert (tmp_path / "p6.txt").read_text().split()[3] == "1.234568e+01"
    write_poses(tmp_path / "p12.txt", pose[None])
    assert (tmp_path / "p12.txt").read_text().split()[3] == "1.234567890000e+01"
    write_calib(tmp_path / "c.txt", {"Tr": pose}, float_format=".6e")
    assert (tmp_path / "c.txt").read_text().startswith("Tr: 1.000000e+00 0.000000e+00")
    write_times(tmp_path / "t.txt", np.array([0.0, 0.1, 12.5]))
    assert (tmp_path / "t.txt").read_text() == "0.000000e+00\n1.000000e-01\n1.250000e+01\n"


# ---------------------------------------------------------------------------------------------
# ensure_sample
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_ensure_sample_replaces_a_sample_of_other_parameters(tmp_path, monkeypatch) -> None:
    from flic_cli.sample import ensure_sample

    target = tmp_path / "cache"
    monkeypatch.setenv("FLIC_SAMPLE_DIR", str(target))
    ensure_sample(frames=2, seed=0)
    paths = ensure_sample(frames=1, seed=3)
    assert (target / ".complete").read_text() == "seed=3 frames=1 kitti_width=2048\n"
    assert entries(paths.kitti_sequence / "velodyne") == ["000000.bin"]
    assert entries(tmp_path) == ["cache"]


@pytest.mark.slow
def test_ensure_sample_reuses_a_cache_written_before_the_split(tmp_path, monkeypatch) -> None:
    """A cache holding the same files and marker (as the former single module wrote them)."""
    from flic_cli.sample import ensure_sample

    target = tmp_path / "cache"
    monkeypatch.setenv("FLIC_SAMPLE_DIR", str(target))
    write_sample(target, frames=1)
    (target / ".complete").write_text("seed=0 frames=1 kitti_width=2048\n")
    stamp = (target / "moosmann" / "scan00000.png").stat().st_mtime_ns
    ensure_sample(frames=1, seed=0)
    assert (target / "moosmann" / "scan00000.png").stat().st_mtime_ns == stamp


def test_ensure_sample_refuses_a_folder_of_other_files(tmp_path, monkeypatch) -> None:
    from flic_cli.sample import ensure_sample

    (tmp_path / "mine.txt").write_text("keep me\n")
    monkeypatch.setenv("FLIC_SAMPLE_DIR", str(tmp_path))
    with pytest.raises(FlicInputError, match="other files than a flic sample"):
        ensure_sample(frames=1)
    assert entries(tmp_path) == ["mine.txt"]


@pytest.mark.slow
def test_a_link_to_a_folder_receives_the_sample(tmp_path) -> None:
    real = tmp_path / "real"
    real.mkdir()
    (tmp_path / "link").symlink_to(real)
    paths = write_sample(tmp_path / "link", frames=1)
    assert (tmp_path / "link").is_symlink()
    assert entries(real) == ["moosmann", "semantickitti"]
    assert paths.kitti_root == tmp_path / "link" / "semantickitti"
    write_sample(tmp_path / "link", frames=1, seed=2)  # replaced through the link
    assert (tmp_path / "link").is_symlink() and entries(tmp_path) == ["link", "real"]
