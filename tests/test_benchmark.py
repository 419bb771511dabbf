"""`flic benchmark` smoke tests: shape and consistency of the outputs (no timing assertions)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from flic_cli.cli import app
from flic_cli.runs.benchmark import HIST_EDGES_MS, STAGES

runner = CliRunner()
METHODS = ["flic0", "flic1", "bogoslavskyi", "dbscan"]
OUTPUTS = [
    "frames.csv",
    "summary.csv",
    "histogram.csv",
    "environment.json",
    "runtime.png",
    "boxplot_hz.png",
    "histogram.png",
]
ENV_KEYS = {
    "cpu",
    "cores_logical",
    "python",
    "versions",
    "threads",
    "command",
    "date",
    "warmup",
    "slow_every",
    "repeat",
    "format",
}


def _bench(data: Path, out: Path, *extra: str):
    return runner.invoke(
        app,
        [
            "benchmark",
            str(data),
            "--methods",
            ",".join(METHODS),
            "--dbscan-every",
            "2",
            "--warmup",
            "1",
            "--out",
            str(out),
            *extra,
        ],
    )


def _check_outputs(out: Path, n_frames: int, methods: list[str], dbscan_frames: list[int]):
    for name in OUTPUTS:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert not list(out.glob(".*tmp*")), "temporary files left behind"

    frames = pd.read_csv(out / "frames.csv")
    assert list(frames.columns) == [
        "method",
        "index",
        "sequence",
        "frame",
        "milliseconds",
        "points",
        "clusters",
    ]
    assert (frames["milliseconds"] > 0).all()
    for m in [*methods, *STAGES]:
        sub = frames[frames["method"] == m]
        expected = dbscan_frames if m == "dbscan" else list(range(n_frames))
        assert sorted(sub["index"]) == expected, m
        assert not sub.duplicated("index").any()
        if m in methods:
            assert (sub["clusters"] >= 0).all() and sub["clusters"].notna().all()
        else:
            assert sub["clusters"].isna().all()
    # every method sees the same evaluated point set per frame
    pts = frames[frames["method"].isin(methods)].groupby("index")["points"].nunique()
    assert (pts == 1).all()

    summary = pd.read_csv(out / "summary.csv").set_index("method")
    assert list(summary.index) == [*methods, *STAGES]
    assert (summary.loc[methods, "kind"] == "method").all()
    assert (summary.loc[list(STAGES), "kind"] == "stage").all()
    for m in summary.index:
        ms = frames.loc[frames["method"] == m, "milliseconds"].to_numpy()
        row = summary.loc[m]
        assert row["frames"] == len(ms)
        assert row["median_ms"] == pytest.approx(np.median(ms))
        assert row["mean_ms"] == pytest.approx(np.mean(ms))
        assert row["max_ms"] == pytest.approx(ms.max())
        assert row["p99_ms"] == pytest.approx(np.percentile(ms, 99))
        assert row["p5_ms"] <= row["median_ms"] <= row["p95_ms"] <= row["p99_ms"] <= row["max_ms"]
        assert row["hz_median"] == pytest.approx(1000.0 / row["median_ms"])
        assert row["hz_mean"] == pytest.approx(1000.0 / row["mean_ms"])
        assert row["stability"] == pytest.approx(row["p99_ms"] / row["median_ms"])
    # speed-ups: ratio of the medians over the frames both methods were timed on
    series = {m: frames[frames["method"] == m].set_index("index")["milliseconds"] for m in methods}
    for a in methods:
        for b in methods:
            common = series[a].index.intersection(series[b].index)
            expected = np.median(series[b][common]) / np.median(series[a][common])
            assert summary.loc[a, f"speedup_vs_{b}"] == pytest.approx(expected)
            if "dbscan" not in (a, b):
                ratio = summary.loc[b, "median_ms"] / summary.loc[a, "median_ms"]
                assert summary.loc[a, f"speedup_vs_{b}"] == pytest.approx(ratio)
        assert summary.loc[a, f"speedup_vs_{a}"] == pytest.approx(1.0)
    assert summary.loc[list(STAGES), [f"speedup_vs_{m}" for m in methods]].isna().all().all()

    hist = pd.read_csv(out / "histogram.csv")
    assert list(hist.columns) == ["method", "bin_lo_ms", "bin_hi_ms", "count"]
    for m in summary.index:
        h = hist[hist["method"] == m]
        assert np.allclose(h["bin_lo_ms"], HIST_EDGES_MS[:-1])
        assert np.allclose(h["bin_hi_ms"], HIST_EDGES_MS[1:])
        assert h["count"].sum() == summary.loc[m, "frames"]

    env = json.loads((out / "environment.json").read_text())
    assert ENV_KEYS <= set(env)
    assert {"numpy", "scipy", "numba", "sklearn"} <= set(env["versions"])
    assert env["threads"]["requested"] == 1 and env["threads"]["numba"] == 1
    assert set(env["warmup"]["first_call_ms"]) == {*methods, *STAGES}
    assert env["slow_every"] == 2
    return frames, summary, env


@pytest.mark.slow
def test_benchmark_moosmann_log(small_sample, tmp_path):
    out = tmp_path / "bench"
    result = _bench(small_sample.moosmann_log, out)
    assert result.exit_code == 0, result.output
    _, _, env = _check_outputs(out, 3, METHODS, dbscan_frames=[0, 2])
    assert env["format"] == "moosmann"
    assert "dbscan: timed only on frames with index % 2 == 0 (2 of 3 frames" in result.output
    assert "environment:" in result.output and "first call incl. JIT" in result.output
    assert "median_ms" in result.output


@pytest.mark.slow
def test_benchmark_semantickitti(small_sample, tmp_path):
    out = tmp_path / "bench"
    result = _bench(small_sample.kitti_root, out, "--repeat", "2", "--no-plots")
    assert result.exit_code == 0, result.output
    assert not (out / "runtime.png").exists()
    for name in ["runtime.png", "boxplot_hz.png", "histogram.png"]:
        (out / name).write_bytes(b"x")  # plots are checked in the Moosmann test
    _, _, env = _check_outputs(out, 3, METHODS, dbscan_frames=[0, 2])
    assert env["format"] == "semantickitti" and env["repeat"] == 2


@pytest.mark.slow
def test_benchmark_frame_selection_and_threads(small_sample, tmp_path):
    out = tmp_path / "bench"
    result = runner.invoke(
        app,
        [
            "benchmark",
            str(small_sample.moosmann_log),
            "--methods",
            "flic0",
            "--frames",
            "1:3",
            "--warmup",
            "0",
            "--threads",
            "2",
            "--out",
            str(out),
        ],
    )
    assert result.exit_code == 0, result.output
    frames = pd.read_csv(out / "frames.csv")
    assert sorted(frames.loc[frames["method"] == "flic0", "frame"]) == [1, 2]
    env = json.loads((out / "environment.json").read_text())
    assert env["threads"]["requested"] == 2
    assert env["warmup"]["first_call_ms"] == {}
    assert "no warm-up" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--methods", "flic0,nope"], "unknown method 'nope'"),
        (["--dbscan-every", "0"], "--slow-every"),
        (["--threads", "0"], "--threads"),
    ],
)
def test_benchmark_bad_input(small_sample, tmp_path, args, message):
    result = runner.invoke(
        app, ["benchmark", str(small_sample.moosmann_log), "--out", str(tmp_path), *args]
    )
    assert result.exit_code == 2
    assert message in result.output
    assert "Traceback" not in result.output


@pytest.mark.slow
def test_speedups_on_few_frames_are_marked_as_indications(small_sample, tmp_path):
    from flic_cli.config import load_config
    from flic_cli.runs.benchmark import run_benchmark
    from flic_cli.runs.spec import BenchmarkRun, Selection

    sel = Selection(small_sample.moosmann_log, config=load_config(), progress=False)
    result = run_benchmark(
        BenchmarkRun(sel, tmp_path / "b", ["flic0", "dbscan"], warmup=1, slow_every=2, plots=False)
    )
    text = result.report()
    assert "~: fewer than 30 frames timed (flic0 n = 3, dbscan n = 2)" in text
    assert "e+" not in text.split("speed-up")[1]  # no exponents in the ratios


@pytest.mark.slow
def test_rounds_keep_each_frames_median(small_sample, tmp_path, monkeypatch):
    """--rounds N: N passes over the selection, each frame's time the median over the passes."""
    from flic_cli.config import load_config
    from flic_cli.runs import benchmark
    from flic_cli.runs.spec import BenchmarkRun, Selection

    times = iter([float(t) for t in range(1, 1000)])
    monkeypatch.setattr(benchmark, "_timed", lambda func, repeat: (func(), 1e6 * next(times)))
    sel = Selection(small_sample.moosmann_log, config=load_config(), progress=False)
    result = benchmark.run_benchmark(
        BenchmarkRun(sel, tmp_path / "b", ["flic0"], warmup=0, rounds=3, plots=False)
    )
    flic0 = result.frames[result.frames["method"] == "flic0"]
    assert len(flic0) == 3 and result.environment["rounds"] == 3
    # every round has a pass for the stages (read and project per frame: calls 1-6 in round 1)
    # and one for flic0 (only flic0 is timed), in turns: round 1 stages then flic0 (calls 7, 8,
    # 9), round 2 flic0 (10, 11, 12) then the stages (13-18), round 3 stages (19-24) then flic0
    # (25, 26, 27); each frame's time is its median over the rounds, the round 2 value
    assert flic0["milliseconds"].tolist() == [10.0, 11.0, 12.0]
    reads = result.frames[result.frames["method"] == "read"]["milliseconds"].tolist()
    assert reads == [13.0, 15.0, 17.0]  # the stage passes' reads: (1, 13, 19), (3, 15, 21), ...
