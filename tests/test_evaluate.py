"""`flic evaluate`: outputs, consistency with per_object.csv, parallel and distributed runs equal
the serial run, resume after an interruption, missing labels, real data."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from flic_cli.cli import app
from flic_cli.errors import FlicInputError
from flic_cli.metrics import IOU_THRESHOLDS
from flic_cli.runs.parallel import imap_frames, resolve_jobs
from flic_cli.runs.scoring import FRAME_COLUMNS, OBJECT_COLUMNS
from flic_cli.runs.tables import SCORE_COLUMNS, TABLE_COLUMNS

runner = CliRunner()
METHODS = "bogoslavskyi,flic1,flic14"
TABLES = [
    "table.csv",
    "per_setting.csv",
    "per_sequence.csv",
    "by_class.csv",
    "by_distance.csv",
    "per_frame.csv",
    "per_object.csv",
    "panoptic.csv",
    "quality_speed.csv",
]
#: Columns that hold wall-clock times, which differ between any two runs.
TIMING = ["seconds", "ground_seconds", "ms_per_frame_median"]


def _evaluate(data: Path, out: Path, *extra: str):
    return runner.invoke(
        app, ["evaluate", str(data), "--methods", METHODS, "--out", str(out), *extra]
    )


@pytest.fixture(scope="module")
def reference(sample_root: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The serial, uninterrupted run (both settings)."""
    out = tmp_path_factory.mktemp("eval") / "ref"
    result = _evaluate(sample_root, out)
    assert result.exit_code == 0, result.output
    assert "iou_mu_no_ground" in result.output
    return out


def _read(path: Path) -> pd.DataFrame:
    return pd.read_csv(path, dtype={"sequence": str}, keep_default_na=False, na_values=[""])


def _assert_same_tables(a: Path, b: Path) -> None:
    for name in TABLES:
        da, db = _read(a / name), _read(b / name)
        da = da.drop(columns=[c for c in TIMING if c in da])
        db = db.drop(columns=[c for c in TIMING if c in db])
        pd.testing.assert_frame_equal(da, db, check_exact=True, obj=name)


@pytest.mark.slow
def test_outputs_and_columns(reference: Path) -> None:
    for name in [*TABLES, "run.json"]:
        assert (reference / name).is_file(), name
    assert list(_read(reference / "table.csv").columns) == list(TABLE_COLUMNS)
    assert list(_read(reference / "per_object.csv").columns) == list(OBJECT_COLUMNS)
    assert list(_read(reference / "per_frame.csv").columns) == list(FRAME_COLUMNS)
    table = _read(reference / "table.csv")
    assert table["method"].tolist() == METHODS.split(",")
    assert (table["p_setting"] == "no-ground").all()
    by_class = _read(reference / "by_class.csv")
    assert {"method", "setting", "class", "class_name", "objects", *SCORE_COLUMNS} <= set(
        by_class.columns
    )
    by_distance = _read(reference / "by_distance.csv")
    assert set(by_distance["band"]) <= {"0-20", "20-40", ">40"}
    per_sequence = _read(reference / "per_sequence.csv")
    assert {"frames", "objects", "iou_mu", "p_mu"} <= set(per_sequence.columns)
    # no temporary files left behind
    assert not list(reference.rglob(".*tmp*"))


def _scores(ious: np.ndarray) -> dict[str, float]:
    out = {"iou_mu": round(100 * ious.mean(), 2)}
    shares = [np.mean(ious >= x - 1e-12) for x in IOU_THRESHOLDS]
    out.update(
        {f"p_{x:.2f}": round(100 * s, 2) for x, s in zip(IOU_THRESHOLDS, shares, strict=True)}
    )
    out["p_mu"] = round(100 * float(np.mean(shares)), 2)
    return out


@pytest.mark.slow
def test_tables_recompute_from_per_object(reference: Path) -> None:
    objects = _read(reference / "per_object.csv")
    frames = _read(reference / "per_frame.csv")
    table = _read(reference / "table.csv").set_index("method")
    per_setting = _read(reference / "per_setting.csv").set_index(["method", "setting"])
    for (method, setting), group in objects.groupby(["method", "setting"]):
        expected = _scores(group["iou"].to_numpy())
        row = per_setting.loc[(method, setting)]
        for key, value in expected.items():
            assert row[key] == pytest.approx(value, abs=1e-9), (method, setting, key)
        assert row["objects"] == len(group)
        if setting == "no-ground":
            for key in ("p_mu", "p_0.50", "p_0.75", "p_0.95"):
                assert table.loc[method, key] == pytest.approx(expected[key], abs=1e-9)
            assert table.loc[method, "objects"] == len(group)
        col = "iou_mu_no_ground" if setting == "no-ground" else "iou_mu_ground"
        assert table.loc[method, col] == pytest.approx(expected["iou_mu"], abs=1e-9)
        # per-frame object counts agree with the per-object rows
        f = frames[(frames["method"] == method) & (frames["setting"] == setting)]
        assert f["objects"].sum() == len(group)
        assert row["frames"] == len(f) == 3
    # objects are the same in both settings (the ground classes hold no instances)
    for _, group in objects.groupby("method"):
        ng = group[group["setting"] == "no-ground"]
        g = group[group["setting"] == "ground"]
        assert ng[["frame", "instance", "class", "points"]].values.tolist() == (
            g[["frame", "instance", "class", "points"]].values.tolist()
        )
    by_class = _read(reference / "by_class.csv")
    for _, row in by_class.iterrows():
        sel = objects[
            (objects["method"] == row["method"])
            & (objects["setting"] == row["setting"])
            & (objects["class"] == row["class"])
        ]
        assert row["objects"] == len(sel)
        assert row["iou_mu"] == pytest.approx(_scores(sel["iou"].to_numpy())["iou_mu"])
    by_distance = _read(reference / "by_distance.csv")
    for _, row in by_distance.iterrows():
        sel = objects[
            (objects["method"] == row["method"])
            & (objects["setting"] == row["setting"])
            & (objects["band"] == row["band"])
        ]
        d = sel["distance_m"]
        lo, hi = {"0-20": (0, 20), "20-40": (20, 40), ">40": (40, np.inf)}[row["band"]]
        assert ((d >= lo - 1e-3) & (d < hi + 1e-3)).all()
        assert row["p_mu"] == pytest.approx(_scores(sel["iou"].to_numpy())["p_mu"])
    assert (objects["points"] >= 100).all()
    assert objects["iou"].between(0, 1).all()


@pytest.mark.slow
def test_jobs_2_equals_serial(reference: Path, sample_root: Path, tmp_path: Path) -> None:
    result = _evaluate(sample_root, tmp_path / "j2", "--jobs", "2")
    assert result.exit_code == 0, result.output
    _assert_same_tables(reference, tmp_path / "j2")


@pytest.mark.slow
def test_dask_local_cluster_equals_serial(
    reference: Path, sample_root: Path, tmp_path: Path
) -> None:
    """Two worker processes (not threads), as on a cluster: the segmenters travel pickled."""
    distributed = pytest.importorskip("distributed", reason="dask.distributed not installed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        protocol="tcp://",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        result = _evaluate(sample_root, tmp_path / "dask", "--scheduler", cluster.scheduler_address)
    assert result.exit_code == 0, result.output
    _assert_same_tables(reference, tmp_path / "dask")


def test_scheduler_without_dask(
    sample_root: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)
    result = _evaluate(sample_root, tmp_path / "x", "--scheduler", "tcp://127.0.0.1:1")
    assert result.exit_code == 2
    assert "pip install" in result.output and "Traceback" not in result.output


@pytest.mark.slow
def test_resume_after_interruption(reference: Path, sample_root: Path, tmp_path: Path) -> None:
    out = tmp_path / "resumed"
    shutil.copytree(reference, out)
    # interrupted: frame 1 unfinished (its objects part written, its frames part not), a
    # temporary file of a killed write, frame 2 never started, no final tables yet
    parts = out / "parts" / "00"
    (parts / "000001.frames.csv").unlink()
    (parts / "000002.frames.csv").unlink()
    (parts / "000002.objects.csv").unlink()
    (parts / ".000002.objects.csv.tmp-99999").write_text("method,set")
    for name in TABLES:
        (out / name).unlink()

    again = _evaluate(sample_root, out)
    assert again.exit_code == 2
    assert "--resume" in again.output

    other = _evaluate(sample_root, out, "--resume", "--setting", "no-ground")
    assert other.exit_code == 2
    assert "different run" in other.output and "settings" in other.output

    result = _evaluate(sample_root, out, "--resume")
    assert result.exit_code == 0, result.output
    assert "1 finished earlier" in result.output
    assert not list(parts.glob(".*tmp*"))
    _assert_same_tables(reference, out)
    # the frame finished before the interruption was not evaluated again
    assert _read(parts / "000000.frames.csv").equals(
        _read(reference / "parts" / "00" / "000000.frames.csv")
    )


@pytest.mark.slow
def test_resume_of_finished_run_rewrites_tables(reference: Path, sample_root: Path, tmp_path):
    out = tmp_path / "done"
    shutil.copytree(reference, out)
    (out / "table.csv").unlink()
    result = _evaluate(sample_root, out, "--resume")
    assert result.exit_code == 0, result.output
    _assert_same_tables(reference, out)


@pytest.fixture
def partly_labelled(sample_root: Path, tmp_path: Path) -> Path:
    root = tmp_path / "kitti"
    shutil.copytree(sample_root, root)
    (root / "sequences" / "00" / "labels" / "000001.label").unlink()
    return root


def test_missing_label_is_named(partly_labelled: Path, tmp_path: Path) -> None:
    result = _evaluate(partly_labelled, tmp_path / "m", "--methods", "flic0")
    assert result.exit_code == 2
    assert "000001.label" in result.output
    assert "Traceback" not in result.output


@pytest.mark.slow
def test_skip_missing(partly_labelled: Path, reference: Path, tmp_path: Path) -> None:
    out = tmp_path / "skip"
    result = _evaluate(partly_labelled, out, "--skip-missing", "--setting", "no-ground")
    assert result.exit_code == 0, result.output
    assert "left out 1 frames without .label files" in result.output
    objects = _read(out / "per_object.csv")
    assert sorted(objects["frame"].unique()) == [0, 2]
    ref = _read(reference / "per_object.csv")
    ref = ref[(ref["setting"] == "no-ground") & (ref["frame"] != 1)].reset_index(drop=True)
    pd.testing.assert_frame_equal(objects, ref)


def test_unlabelled_data_is_refused(tmp_path: Path) -> None:
    from flic_cli.sample import write_sample

    paths = write_sample(tmp_path / "s", frames=1)
    result = _evaluate(paths.moosmann_log, tmp_path / "o", "--methods", "flic0")
    assert result.exit_code == 2
    assert "labels" in result.output


@pytest.mark.slow
def test_corrupt_frame_in_worker(sample_root: Path, tmp_path: Path) -> None:
    root = tmp_path / "kitti"
    shutil.copytree(sample_root, root)
    bad = root / "sequences" / "00" / "velodyne" / "000002.bin"
    bad.write_bytes(bad.read_bytes()[:-4])
    result = _evaluate(root, tmp_path / "o", "--methods", "flic0", "--jobs", "2")
    assert result.exit_code == 2
    assert "000002.bin" in result.output and "multiple of 16" in result.output
    # the frames that finished are kept for --resume
    assert (tmp_path / "o" / "run.json").is_file()


def test_bad_options(sample_root: Path, tmp_path: Path) -> None:
    for extra, words in (
        (["--methods", "nope"], "unknown method"),
        (["--setting", "sideways"], "--setting"),
        (["--ground-remover", "magic"], "ground remover"),
    ):
        result = _evaluate(sample_root, tmp_path / "o", *extra)
        assert result.exit_code == 2, extra
        assert words in result.output


def _square(x: int) -> int:
    return x * x


@pytest.mark.slow
def test_imap_frames() -> None:
    assert list(imap_frames(_square, range(5), jobs=1)) == [0, 1, 4, 9, 16]
    assert sorted(imap_frames(_square, range(7), jobs=2)) == [x * x for x in range(7)]


def test_imap_frames_without_dask(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(FlicInputError, match="flic\\[distributed\\]"):
        list(imap_frames(_square, range(2), scheduler="tcp://127.0.0.1:1"))


@pytest.mark.slow
def test_real_data_sequence_00_frame_0(kitti_root: Path, tmp_path: Path) -> None:
    result = runner.invoke(
        app,
        [
            "evaluate",
            str(kitti_root),
            "--methods",
            "flic0",
            "--sequences",
            "00",
            "--frames",
            "0:1",
            "--setting",
            "no-ground",
            "--out",
            str(tmp_path / "real"),
        ],
    )
    assert result.exit_code == 0, result.output
    table = _read(tmp_path / "real" / "table.csv")
    assert table["objects"].tolist() == [7]
    assert np.isnan(table["iou_mu_ground"]).all()
    assert 0 < table["iou_mu_no_ground"].iloc[0] <= 100


@pytest.mark.slow
def test_imap_frames_dask_window() -> None:
    distributed = pytest.importorskip("distributed", reason="dask.distributed not installed")
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        protocol="tcp://",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        got = list(imap_frames(_square, range(25), scheduler=cluster.scheduler_address))
    assert sorted(got) == [x * x for x in range(25)]


@pytest.mark.slow
def test_dask_cluster_started_from_the_command_line(
    reference: Path, sample_root: Path, tmp_path: Path
) -> None:
    """docs/distributed.md's multi-machine recipe on one machine: `dask scheduler` and `dask worker`
    started as commands, `flic evaluate --scheduler` sends the frames to them."""
    import json
    import subprocess
    import time

    pytest.importorskip("distributed", reason="dask.distributed not installed")
    dask = Path(sys.executable).parent / "dask"
    file = tmp_path / "scheduler.json"
    procs = [
        subprocess.Popen(
            [
                dask,
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                file,
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    ]
    try:
        for _ in range(300):
            if file.is_file() and file.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(file.read_text())["address"]
        procs.append(
            subprocess.Popen(
                [dask, "worker", address, "--nworkers", "2", "--nthreads", "1", "--no-dashboard"],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        result = _evaluate(sample_root, tmp_path / "cli", "--scheduler", address)
    finally:
        for proc in reversed(procs):
            proc.terminate()
            proc.wait(timeout=30)
    assert result.exit_code == 0, result.output
    _assert_same_tables(reference, tmp_path / "cli")


def test_estimate_line() -> None:
    from flic_cli.runs.evaluate import estimate_line
    from flic_cli.runs.scoring import FrameScores

    timing = []
    for wall, dbscan in ((2.0, 1.5), (1.0, 0.5), (1.2, 0.6)):
        scores = FrameScores("00", 0)
        scores.frames["method"] += ["flic0", "dbscan"]
        scores.frames["seconds"] += [0.002, dbscan]
        scores.frames["ground_seconds"] += [0.0, 0.0]
        timing.append((wall, scores))
    line = estimate_line(timing, 1000, jobs=4, scheduler=None)
    # median frame 1.2 s, dbscan 0.6 s, flic0 2 ms, the rest the median of 0.498, 0.498, 0.598
    assert line.startswith("estimate from 3 frame(s): 1.2 s per frame (flic0 2 ms, dbscan 600 ms;")
    workers = resolve_jobs(4, 1000)  # --jobs is clamped to the CPU cores
    assert "scoring 500 ms) x 1000 frames = 20.0 min of one worker" in line
    if workers > 1:
        assert f" / {workers} processes = {20.0 / workers:.1f} min" in line
    assert "dask worker threads" in estimate_line(timing, 10, jobs=1, scheduler="tcp://x:1")


def test_estimate_line_counts_a_shared_ground_extraction_once() -> None:
    from flic_cli.runs.evaluate import estimate_line
    from flic_cli.runs.scoring import FrameScores

    # two methods of 10 ms each, both using one 30 ms ground mask: 1.0 s of wall time is
    # 20 ms of clustering, 30 ms of ground extraction and 950 ms of the rest
    scores = FrameScores("00", 0)
    scores.frames["method"] += ["flic0", "flic14"]
    scores.frames["seconds"] += [0.040, 0.040]
    scores.frames["ground_seconds"] += [0.030, 0.030]
    scores.ground["seconds"].append(0.030)
    line = estimate_line([(1.0, scores)], 10, jobs=1, scheduler=None)
    assert "(flic0 40 ms, flic14 40 ms, each with its ground extraction;" in line
    assert "the ground extraction once per frame 30 ms;" in line
    assert "reading, projection and scoring 950 ms) x 10 frames = 10 s of one worker" in line


@pytest.mark.slow
def test_table_intervals_hold_the_estimates(reference: Path) -> None:
    table = _read(reference / "table.csv")
    for col in ("iou_mu_no_ground", "iou_mu_ground", "p_mu"):
        assert (table[f"{col}_low"] <= table[col]).all() and (
            table[col] <= table[f"{col}_high"]
        ).all()
        assert (table[f"{col}_low"] < table[f"{col}_high"]).all()  # 3 frames: not degenerate


@pytest.mark.slow
def test_quality_speed_from_a_benchmark(reference: Path, sample_root: Path, tmp_path: Path) -> None:
    qs = _read(reference / "quality_speed.csv")
    table = _read(reference / "table.csv")
    assert qs["method"].tolist() == table["method"].tolist()
    np.testing.assert_array_equal(qs["iou_mu"], table["iou_mu_no_ground"])
    assert (qs["timing"] == "flic evaluate (no-ground setting)").all()
    assert (reference / "quality_speed.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bench = tmp_path / "bench"
    bench.mkdir()
    pd.DataFrame({"method": ["flic1"], "median_ms": [0.25], "frames": [40]}).to_csv(
        bench / "summary.csv", index=False
    )
    result = _evaluate(sample_root, tmp_path / "o", "--setting", "no-ground", "--runtimes", bench)
    assert result.exit_code == 0, result.output
    qs = _read(tmp_path / "o" / "quality_speed.csv").set_index("method")
    assert qs.loc["flic1", "ms_per_frame_median"] == 0.25 and qs.loc["flic1", "frames_timed"] == 40
    assert qs.loc["flic1", "timing"] == "flic benchmark"
    assert qs.loc["flic14", "timing"].startswith("flic evaluate")  # not in the benchmark


@pytest.mark.slow
def test_oracle_panoptic_equals_scoring_what_segment_writes(
    sample_root: Path, tmp_path: Path
) -> None:
    """`flic evaluate --semantics oracle` reports the PQ of exactly the files that
    `flic segment --semantics oracle` writes (as semantic-kitti-api would score them)."""
    from flic_cli.io import open_dataset, read_label
    from flic_cli.metrics.panoptic import PanopticCounts, class_scores, panoptic_counts

    result = _evaluate(sample_root, tmp_path / "e", "--methods", "flic14", "--semantics", "oracle")
    assert result.exit_code == 0, result.output
    seg = runner.invoke(
        app,
        [
            "segment",
            str(sample_root),
            "--method",
            "flic14",
            "--semantics",
            "oracle",
            "--out",
            str(tmp_path / "s"),
        ],
    )
    assert seg.exit_code == 0, seg.output
    counts = []
    for ref in open_dataset(sample_root).refs():
        pred = np.fromfile(
            tmp_path / "s" / "sequences" / ref.sequence / "predictions" / f"{ref.frame:06d}.label",
            dtype="<u4",
        )
        counts.append(panoptic_counts(read_label(ref.label_path), pred))
    pooled = PanopticCounts.total(counts, 20)
    scores = class_scores(pooled)
    pan = _read(tmp_path / "e" / "panoptic.csv")
    oracle = pan[pan["semantics"] == "oracle"].set_index("class")
    from flic_cli.classes import LEARNING_NAMES

    for c in range(1, 20):
        row = oracle.loc[LEARNING_NAMES[c]]
        assert row["pq"] == round(100 * scores["pq"][c], 2)
        assert (row["tp"], row["fp"], row["fn"]) == (pooled.tp[c], pooled.fp[c], pooled.fn[c])
    assert oracle.loc["person", "tp"] > 0  # the sample has people, and they are scored


@pytest.mark.slow
def test_ground_csv_pools_each_removers_counts(sample_root: Path, tmp_path: Path) -> None:
    """ground.csv: per remover of the ground setting, the counts of its mask against the
    ground classes, pooled over frames (recomputed here frame by frame)."""
    from flic_cli.config import load_config
    from flic_cli.io import open_dataset
    from flic_cli.metrics.ground import GroundCounts, ground_counts, ground_scores, point_ground
    from flic_cli.runs.pipeline import prepare

    result = _evaluate(
        sample_root,
        tmp_path / "g",
        "--methods",
        "flic0,bogoslavskyi",
        "--setting",
        "ground",
        "--ground-remover",
        "own",
    )
    assert result.exit_code == 0, result.output
    table = _read(tmp_path / "g" / "ground.csv").set_index("remover")
    assert list(table.index) == ["column", "bogoslavskyi"]
    assert "ground extraction column: precision" in result.output
    cfg = load_config()
    ds = open_dataset(sample_root)
    for name in table.index:
        total = GroundCounts()
        for ref in ds.refs():
            prep = prepare(ds.load(ref), "ground", cfg.projection)
            mask = cfg.remover(name).extract(prep.image, prep.points).mask
            total = total + ground_counts(prep.labels, point_ground(prep.image, mask))
        expected = ground_scores(total)
        for key in ("precision", "recall", "f1", "things_removed"):
            assert table.loc[name, key] == round(expected[key], 2), (name, key)
        assert table.loc[name, "frames"] == len(ds.refs())
