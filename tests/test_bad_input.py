"""Every bad input gets one line ``error: <file or option>: <what is wrong>``, exit code 2, no
traceback, and leaves no output behind: one table of cases, run through the installed entry
point (:func:`flic_cli.cli.main`)."""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from oracles import file_tree
from PIL import Image

from flic_cli.cli import main


@dataclass
class Env:
    """The data of one case, in its own folder: a copy of the 3-frame sample."""

    tmp: Path
    kitti: Path  # SemanticKITTI root
    log: Path  # Moosmann log folder
    out: Path  # the output folder of the run (must not appear)

    @property
    def seq(self) -> Path:
        return self.kitti / "sequences" / "00"

    def bin(self, frame: int = 1) -> Path:
        return self.seq / "velodyne" / f"{frame:06d}.bin"

    def label(self, frame: int = 1) -> Path:
        return self.seq / "labels" / f"{frame:06d}.label"

    def png(self, frame: int = 1) -> Path:
        return next(self.log.rglob(f"scan{frame:05d}.png"))

    def cfg(self, text: str) -> Path:
        path = self.tmp / "my.toml"
        path.write_text(text)
        return path


@dataclass
class Case:
    """``argv`` may hold ``{kitti}``, ``{log}``, ``{out}``, ``{tmp}``, ``{cfg}``, ``{seq}``;
    ``setup`` breaks the data (and returns the config file text for ``{cfg}``, if any);
    ``names`` is what the error line must name (``{...}`` filled in as for argv)."""

    id: str
    argv: list[str]
    names: list[str]
    setup: Callable[[Env], str | None] | None = None


def _truncate(path_of: Callable[[Env], Path], keep: int) -> Callable[[Env], None]:
    def setup(env: Env) -> None:
        path = path_of(env)
        path.write_bytes(path.read_bytes()[:keep] if keep >= 0 else path.read_bytes()[:keep])

    return setup


def _write(path_of: Callable[[Env], Path], data: bytes) -> Callable[[Env], None]:
    def setup(env: Env) -> None:
        path_of(env).write_bytes(data)

    return setup


def _png(mode: str, size: tuple[int, int] | None = None) -> Callable[[Env], None]:
    def setup(env: Env) -> None:
        path = env.png()
        w, h = size or Image.open(path).size
        dtype = np.uint16 if mode == "I;16" else np.uint8
        shape = (h, w, 3) if mode == "RGB" else (h, w)
        Image.fromarray(np.full(shape, 7, dtype=dtype)).save(path, format="PNG")

    return setup


def _img_cfg(text: str) -> Callable[[Env], None]:
    def setup(env: Env) -> None:
        next(env.log.rglob("img.cfg")).write_text(text)

    return setup


def _config(text: str) -> Callable[[Env], str]:
    return lambda env: text


def _nan_scan(env: Env) -> None:
    raw = np.fromfile(env.bin(), dtype="<f4").reshape(-1, 4)
    raw[:, 0] = np.nan
    raw.tofile(env.bin())


def _other_run(env: Env) -> None:
    (env.out / "parts" / "00").mkdir(parents=True)
    (env.out / "parts" / "00" / "000000.frames.csv").write_text("method\n")
    (env.out / "run.json").write_text('{"command": "evaluate", "methods": ["other"]}')


def _plain_file(env: Env) -> None:
    env.out.parent.mkdir(parents=True, exist_ok=True)
    env.out.write_text("not a folder")


SEG = ["segment", "{kitti}", "--out", "{out}"]
SEG_LOG = ["segment", "{log}", "--out", "{out}"]
EVAL = ["evaluate", "{kitti}", "--methods", "flic0", "--out", "{out}"]
BENCH = ["benchmark", "{log}", "--methods", "flic0", "--out", "{out}", "--warmup", "0"]
SWEEP = ["sweep-threshold", "{kitti}", "--out", "{out}", "--frames", "0"]

CASES = [
    # ---- the data
    Case("data-missing", ["segment", "{tmp}/nowhere", "--out", "{out}"], ["{tmp}/nowhere"]),
    Case(
        "data-unknown-format",
        ["segment", "{tmp}/other", "--out", "{out}"],
        ["{tmp}/other", "none of"],
        lambda e: (e.tmp / "other").mkdir(),
    ),
    Case("bin-not-16-bytes", SEG, ["000001.bin", "multiple of 16"], _truncate(Env.bin, -3)),
    Case("bin-empty", SEG, ["000001.bin", "empty"], _write(Env.bin, b"")),
    Case("bin-all-nan", SEG, ["000001.bin", "finite"], _nan_scan),
    Case(
        "label-wrong-count", SEG, ["000001.label", "labels but the scan"], _truncate(Env.label, -8)
    ),
    Case("label-not-4-bytes", SEG, ["000001.label", "multiple of 4"], _truncate(Env.label, -2)),
    Case("label-missing", EVAL, ["000001.label", "missing"], lambda e: e.label().unlink()),
    Case("png-8-bit", SEG_LOG, ["scan00001.png", "8-bit"], _png("L")),
    Case("png-rgb", SEG_LOG, ["scan00001.png", "RGB"], _png("RGB")),
    Case("png-wrong-size", SEG_LOG, ["scan00001.png", "img.cfg says"], _png("I;16", (100, 64))),
    Case("png-garbage", SEG_LOG, ["scan00001.png", "PNG"], _write(Env.png, b"not an image")),
    Case("png-truncated", SEG_LOG, ["scan00001.png"], _truncate(Env.png, 200)),
    Case("img-cfg-missing", SEG_LOG, ["img.cfg"], lambda e: next(e.log.rglob("img.cfg")).unlink()),
    Case(
        "img-cfg-not-number",
        SEG_LOG,
        ["img.cfg", "not a number"],
        _img_cfg("870; 1; 180; -180; abc;"),
    ),
    Case(
        "img-cfg-angle-count",
        SEG_LOG,
        ["img.cfg", "vertical angles"],
        _img_cfg("870; 2; 180; -180; 1;"),
    ),
    Case("img-cfg-width", SEG_LOG, ["img.cfg", "width"], _img_cfg("870.5; 1; 180; -180; 1;")),
    Case(
        "img-cfg-partial-turn",
        SEG_LOG,
        ["img.cfg", "not supported"],
        _img_cfg("870; 1; 90; -90; 1;"),
    ),
    Case(
        "no-labels-for-no-ground", [*SEG_LOG, "--setting", "no-ground"], ["no ground-truth labels"]
    ),
    Case("evaluate-moosmann", ["evaluate", "{log}", "--out", "{out}"], ["{log}", "labels"]),
    # ---- the selection
    Case("unknown-sequence", [*SEG, "--sequences", "07"], ["no sequence 07"]),
    Case("frames-malformed", [*SEG, "--frames", "1-2"], ["invalid frame range"]),
    Case("frames-empty-range", [*SEG, "--frames", "5:3"], ["empty frame range"]),
    Case("frames-none-selected", [*SEG, "--frames", "100:200"], ["no scans", "100:200"]),
    Case("render-not-selected", [*SEG, "--frames", "0:2", "--render", "99"], ["--render 99"]),
    # ---- options
    Case("setting", [*SEG, "--setting", "sideways"], ["--setting"]),
    Case("method", [*SEG, "--method", "nope"], ["unknown method 'nope'"]),
    Case("mc-unknown", [*SEG, "--mc", "3"], ["unknown method 'flic3'"]),
    Case("mc-not-flic", [*SEG, "--method", "dbscan", "--mc", "1"], ["--mc"]),
    Case("ground-remover", [*SEG, "--ground-remover", "magic"], ["ground remover 'magic'"]),
    Case("jobs-not-int", [*SEG, "--jobs", "abc"], ["--jobs"]),
    Case("unknown-option", [*SEG, "--bogus"], ["--bogus"]),
    Case("repeat-zero", [*BENCH, "--repeat", "0"], ["--repeat"]),
    Case("threads-zero", [*BENCH, "--threads", "0"], ["--threads"]),
    Case("sweep-step", [*SWEEP, "--step", "0"], ["--step"]),
    Case("sweep-order", [*SWEEP, "--from", "2", "--to", "1"], ["--to"]),
    Case("sweep-negative", [*SWEEP, "--from", "-1", "--to", "1"], ["--from", "positive"]),
    Case("evaluate-setting", [*EVAL, "--setting", "diagonal"], ["--setting"]),
    # ---- config files
    Case("cfg-missing", [*SEG, "--config", "{tmp}/absent.toml"], ["absent.toml", "does not exist"]),
    Case("cfg-not-toml", [*SEG, "--config", "{cfg}"], ["my.toml", "TOML"], _config("[methods\n")),
    Case(
        "cfg-not-number",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "[methods.flic0] threshold_m"],
        _config('[methods.flic0]\nthreshold_m = "abc"\n'),
    ),
    Case(
        "cfg-negative-threshold",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "threshold_m", "greater than 0"],
        _config("[methods.flic0]\nthreshold_m = -1.0\n"),
    ),
    Case(
        "cfg-min-size-zero",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "min_size"],
        _config("[methods.flic0]\nmin_size = 0\n"),
    ),
    Case(
        "cfg-width-zero",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "[projection] width"],
        _config("[projection]\nwidth = 0\n"),
    ),
    Case(
        "cfg-fov-order",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "fov_up_deg"],
        _config("[projection]\nfov_up_deg = -30.0\n"),
    ),
    Case(
        "cfg-unknown-section",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "[methodz]"],
        _config("[methodz.flic0]\nthreshold_m = 1.0\n"),
    ),
    Case(
        "cfg-unknown-key",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "treshold_m", "unknown key"],
        _config("[methods.flic0]\ntreshold_m = 1.0\n"),
    ),
    Case(
        "cfg-unknown-kind",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "kind"],
        _config('[methods.x]\nkind = "magic"\n'),
    ),
    Case(
        "cfg-bad-map",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "maps"],
        _config("[methods.flic0]\nmaps = [[2, 2, 1]]\n"),
    ),
    Case(
        "cfg-map-step-0",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "maps", "steps >= 1"],
        _config("[methods.flic0]\nmaps = [[0, 2]]\n"),
    ),
    Case(
        "cfg-map-negative-offset",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "maps"],
        _config("[methods.flic0]\nmaps = [[2, 2, -1, 0]]\n"),
    ),
    Case(
        "cfg-bad-mc-mode",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "mc_mode"],
        _config('[methods.flic0]\nmc_mode = "both"\n'),
    ),
    Case(
        "cfg-unknown-ground",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "ground"],
        _config('[methods.flic0]\nground = "magic"\n'),
    ),
    Case(
        "cfg-unknown-remover-table",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "[ground.magic]"],
        _config("[ground.magic]\nx = 1\n"),
    ),
    Case(
        "cfg-like-unknown",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "like"],
        _config('[methods.x]\nlike = "nothing"\n'),
    ),
    Case(
        "cfg-default-methods",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "default_methods"],
        _config('default_methods = ["nothing"]\n'),
    ),
    Case(
        "cfg-bad-window",
        [*SEG, "--config", "{cfg}"],
        ["my.toml", "[ground.bogoslavskyi] window"],
        _config("[ground.bogoslavskyi]\nwindow = 4\n"),
    ),
    # ---- outputs
    Case("out-is-file", SEG, ["{out}", "is an existing file"], _plain_file),
    Case(
        "out-under-file",
        ["segment", "{kitti}", "--out", "{out}/sub"],
        ["{out}/sub", "is a file"],
        _plain_file,
    ),
    Case(
        "out-inside-sequence",
        ["segment", "{kitti}", "--out", "{seq}/pred"],
        ["{seq}/pred", "inside the input"],
    ),
    Case(
        "out-inside-log",
        ["segment", "{log}", "--out", "{log}/pred"],
        ["{log}/pred", "inside the input"],
    ),
    Case("out-other-run", EVAL, ["{out}", "different run"], _other_run),
    # ---- flic sample
    Case("sample-into-file", ["sample", "{out}"], ["{out}"], _plain_file),
    Case("sample-negative-frames", ["sample", "{out}", "--frames", "-5"], ["--frames"]),
]


def _fill(text: str, env: Env) -> str:
    return text.format(
        kitti=env.kitti, log=env.log, out=env.out, tmp=env.tmp, cfg=env.tmp / "my.toml", seq=env.seq
    )


@pytest.fixture
def env(small_sample, tmp_path: Path) -> Env:
    kitti = tmp_path / "kitti"
    log = tmp_path / "log"
    shutil.copytree(small_sample.kitti_root, kitti)
    shutil.copytree(small_sample.moosmann_log, log)
    return Env(tmp_path, kitti, log, tmp_path / "results" / "out")


def test_the_table_is_big_enough() -> None:
    assert len(CASES) >= 40
    assert len({c.id for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case: Case, env: Env, capsys: pytest.CaptureFixture[str]) -> None:
    text = case.setup(env) if case.setup is not None else None
    if text is not None:
        env.cfg(text)
    before = file_tree(env.out)
    cwd = os.getcwd()
    os.chdir(env.tmp)  # nothing may land in the working folder either
    try:
        with pytest.raises(SystemExit) as exit_info:
            main([_fill(a, env) for a in case.argv])
    finally:
        os.chdir(cwd)
    captured = capsys.readouterr()
    assert exit_info.value.code == 2, captured
    lines = [ln for ln in captured.err.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("error: ")]
    assert len(errors) == 1, captured.err
    assert "Traceback" not in captured.err + captured.out
    for word in case.names:
        assert _fill(word, env) in errors[0], errors[0]
    assert file_tree(env.out) == before, "the failed run left output behind"
    assert not (env.tmp / "flic-out").exists()
    leftovers = [p for p in env.tmp.rglob(".*staging*")] + list(env.tmp.rglob(".*.tmp-*"))
    assert not leftovers
