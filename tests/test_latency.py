"""Latency per revolution on recordings (flic_cli.runs.latency), in segment and benchmark."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from flic_cli.runs.latency import summary_line

NEBULA = "sensors/velodyne/nebula_vlp16/1673400471837873222"


def test_summary_line_leaves_the_first_frame_out_and_judges_p99():
    line = summary_line("m", np.array([1000.0, 10, 20, 30, 40]))
    assert "over 4 frames after the first (1000 ms" in line
    assert "median 25.0 ms" in line and "p99 39.7 ms" in line and "max 40.0 ms" in line
    assert "10 Hz (100 ms): yes, 20 Hz (50 ms): yes" in line
    one = summary_line("m", np.array([253.0]))
    assert "latency of the only revolution 253 ms" in one and "too few revolutions" in one
    slow = summary_line("m", np.array([5.0, 40, 40, 40, 60]))
    assert "p99 59.4 ms" in slow and "10 Hz (100 ms): yes, 20 Hz (50 ms): no" in slow


@pytest.mark.slow
def test_benchmark_on_a_bag_writes_the_latency_per_revolution(shared_data, tmp_path):
    pytest.importorskip("rosbags")
    from flic_cli.runs.benchmark import run_benchmark
    from flic_cli.runs.spec import BenchmarkRun, Selection

    sel = Selection(shared_data / NEBULA, progress=False)
    result = run_benchmark(
        BenchmarkRun(sel, tmp_path, ["flic14", "bogoslavskyi"], warmup=1, plots=False)
    )
    lat = pd.read_csv(tmp_path / "latency.csv")
    assert list(lat["method"]) == ["flic14"] * 4 + ["bogoslavskyi"] * 4
    assert list(lat["frame"]) == [0, 1, 2, 3] * 2
    parts = lat["decode_ms"] + lat["project_ms"] + lat["method_ms"]
    assert (lat["total_ms"] >= parts - 1e-3).all() and (lat["total_ms"] <= parts + 5).all()
    assert (lat["decode_ms"] > 0).all() and (lat["points"] > 14000).all()
    report = "\n".join(result.notes)
    assert report.count("latency per revolution") == 2 and "keeps up with 10 Hz" in report
