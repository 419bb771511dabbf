"""A new format and a new clusterer from this test module alone: one registry call each.

``ToyFormat`` holds every frame of a recording in ONE file (``*.toy``: the points and labels of
all frames, concatenated, with each frame's offset), the way a pcap or a bag does; its frames
are addressed by ``FrameRef.index``. ``PixelBlobs`` is a clusterer (the connected components of
the range image's near pixels, scipy's labeller) declaring its sweep range and that it is slow.
Both are registered with :func:`flic_cli.registry.register`; no product file names them. The
recording is the synthetic sample's SemanticKITTI sequence packed into one file, so every output
has an oracle: the same command on the SemanticKITTI sequence, or the clusterer called directly.
"""

from __future__ import annotations

import io
from dataclasses import dataclass as plain_dataclass
from pathlib import Path
from typing import Annotated, ClassVar

import numpy as np
import pandas as pd
import pytest
from pydantic import Field
from pydantic.dataclasses import dataclass
from scipy import ndimage
from typer.testing import CliRunner

from flic_cli import registry
from flic_cli.cli import app
from flic_cli.component import STRICT
from flic_cli.errors import FlicInputError
from flic_cli.io import open_dataset
from flic_cli.io.atomic import atomic_write_bytes
from flic_cli.io.base import Frame, FrameRef, in_frames
from flic_cli.methods.base import drop_small

runner = CliRunner()
pytestmark = pytest.mark.slow  # every test runs flic commands end to end on the toy format

SUFFIX = ".toy"


def write_toy(path: Path, frames: list[tuple[np.ndarray, np.ndarray]]) -> None:
    """Write ``(points (N, 3) float32, labels (N,) uint32)`` of every frame into one file."""
    offsets = np.cumsum([0] + [len(p) for p, _ in frames])
    buf = io.BytesIO()
    np.savez(
        buf,
        points=np.concatenate([p for p, _ in frames]).astype(np.float32),
        labels=np.concatenate([lab for _, lab in frames]).astype(np.uint32),
        offsets=offsets,
    )
    atomic_write_bytes(path, buf.getvalue())


class ToyFormat:
    """Every frame of a recording in one ``.toy`` file (implements :class:`Dataset`)."""

    format = "toy"
    point_semantics = False

    @staticmethod
    def detect(path: Path) -> bool:
        return path.is_file() and path.suffix == SUFFIX

    def __init__(self, root, sequences=None, frames=None, require_labels=False) -> None:
        self.root = Path(root)
        with np.load(self.root) as data:
            n = data["offsets"].size - 1
        name = self.root.stem
        if sequences is not None and sequences != [name]:
            raise FlicInputError(self.root, f"holds one sequence, {name}")
        self._refs = [
            FrameRef(name, k, self.root, self.root, "toy", index=k)
            for k in range(n)
            if in_frames(k, frames)
        ]
        if not self._refs:
            raise FlicInputError(self.root, "no frame selected")

    def refs(self) -> list[FrameRef]:
        return list(self._refs)

    def labelled(self) -> bool:
        return True

    def folders(self) -> list[Path]:
        return [self.root.parent]

    @staticmethod
    def write_prediction(out, ref, labels, image=None, semantics=None) -> Path:
        path = Path(out) / ref.sequence / f"{ref.frame:06d}.npy"
        buf = io.BytesIO()
        np.save(buf, np.asarray(labels, dtype=np.int32))
        atomic_write_bytes(path, buf.getvalue())
        return path

    @staticmethod
    def export_path(out, ref, suffix) -> Path:
        return Path(out) / ref.sequence / f"{ref.frame:06d}{suffix}"

    def load(self, ref: FrameRef) -> Frame:
        with np.load(ref.path) as data:
            lo, hi = data["offsets"][ref.index], data["offsets"][ref.index + 1]
            return Frame(ref, data["points"][lo:hi], data["labels"][lo:hi])


@dataclass(frozen=True, config=STRICT)
class PixelBlobs:
    """Connected components (8-neighbourhood) of the pixels nearer than ``max_range_m``."""

    max_range_m: Annotated[float, Field(gt=0, description="metres")] = 40.0
    min_size: Annotated[int, Field(ge=1, description="points")] = 30
    main_param: ClassVar[str] = "max_range_m"
    sweep_range: ClassVar[tuple[float, float, float]] = (20.0, 40.0, 20.0)
    sweep_label: ClassVar[str] = "largest range [m]"
    slow: ClassVar[bool] = True

    def segment(self, image, points: np.ndarray, ground) -> np.ndarray:
        near = (image.ranges > 0) & (image.ranges < self.max_range_m)
        if ground is not None:
            near &= ~ground.left_out  # the ground step's pixels (and held cells)
        blobs, _ = ndimage.label(near, structure=np.ones((3, 3), dtype=bool))
        return drop_small(image.point_labels(blobs), self.min_size)


@plain_dataclass
class Toy:
    recording: Path
    kitti: Path
    config: Path


@pytest.fixture
def toy(small_sample, tmp_path: Path):
    """The sample's sequence as one ``.toy`` file, the toy format and method registered."""
    from flic_cli.io import read_label, read_scan

    ds = open_dataset(small_sample.kitti_root)
    frames = []
    for ref in ds.refs():
        scan = read_scan(ref.path)
        frames.append((scan.points, read_label(ref.label_path)))
    (tmp_path / "data").mkdir()
    recording = tmp_path / "data" / f"{ds.refs()[0].sequence}{SUFFIX}"
    write_toy(recording, frames)
    config = tmp_path / "toy.toml"
    config.write_text('[methods.blobs]\nkind = "blobs"\nmax_range_m = 40.0\n')
    registry.register(
        "format",
        "toy",
        registry.Entry(f"{__name__}:ToyFormat", "a toy recording", labelled=True,
                       frames_per_file="many"),
    )  # fmt: skip
    registry.register("method", "blobs", registry.Entry(f"{__name__}:PixelBlobs", "toy blobs"))
    yield Toy(recording, small_sample.kitti_root, config)
    registry.unregister("format", "toy")
    registry.unregister("method", "blobs")


def _ok(args: list[str]) -> str:
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    return result.output


def test_segment_writes_the_clusterers_labels_for_every_frame_of_the_file(toy, tmp_path):
    from flic_cli.config import load_config
    from flic_cli.io import read_predictions
    from flic_cli.runs.pipeline import prepare

    cfg = load_config(toy.config)
    for setting, extra in (("no-ground", []), ("ground", ["--ground-remover", "paper"])):
        out = tmp_path / f"seg-{setting}"
        base = ["segment", "--method", "blobs", "--config", str(toy.config), "--setting", setting]
        _ok([*base, str(toy.recording), "--out", str(out), *extra])
        _ok([*base, str(toy.kitti), "--out", str(tmp_path / f"kitti-{setting}"), *extra])
        ds = open_dataset(toy.recording)
        assert [r.index for r in ds.refs()] == [0, 1, 2]
        for ref in ds.refs():
            got = np.load(out / ref.sequence / f"{ref.frame:06d}.npy")
            frame = ds.load(ref)
            assert got.shape == (frame.points.shape[0],)
            # the same labels as segmenting the SemanticKITTI frame the file was packed from
            kitti = read_predictions(tmp_path / f"kitti-{setting}", ref.sequence, ref.frame)
            np.testing.assert_array_equal(got, kitti)
            if setting == "no-ground":  # and as the clusterer called on the prepared frame
                prep = prepare(frame, setting, cfg.projection)
                direct = cfg.method("blobs").method.segment(prep.image, prep.points, None)
                np.testing.assert_array_equal(got, prep.scan_labels(direct))
            assert got.max() >= 1 and 0 < np.count_nonzero(got) < got.size


def test_evaluate_scores_the_file_as_its_source_sequence(toy, tmp_path):
    args = ["--methods", "blobs,flic0", "--config", str(toy.config), "--setting", "both"]
    _ok(["evaluate", str(toy.recording), *args, "--out", str(tmp_path / "toy")])
    _ok(["evaluate", str(toy.kitti), *args, "--out", str(tmp_path / "kitti")])
    got = pd.read_csv(tmp_path / "toy" / "per_object.csv")
    want = pd.read_csv(tmp_path / "kitti" / "per_object.csv")
    assert set(got["method"]) == {"blobs", "flic0"} and len(got) > 0
    pd.testing.assert_frame_equal(got, want)
    table = pd.read_csv(tmp_path / "toy" / "table.csv")
    assert set(table["method"]) == {"blobs", "flic0"}
    ref = pd.read_csv(tmp_path / "kitti" / "table.csv")
    pd.testing.assert_frame_equal(table, ref)


def test_benchmark_times_the_slow_method_on_every_nth_frame(toy, tmp_path):
    out = tmp_path / "bench"
    args = ["benchmark", str(toy.recording), "--methods", "blobs,flic0", "--config"]
    _ok([*args, str(toy.config), "--slow-every", "2", "--warmup", "0", "--no-plots",
         "--out", str(out)])  # fmt: skip
    frames = pd.read_csv(out / "frames.csv", dtype={"sequence": str})
    timed = {m: sorted(set(g["index"])) for m, g in frames.groupby("method")}
    assert timed["flic0"] == [0, 1, 2]
    assert timed["blobs"] == [0, 2]  # declared slow: every 2nd frame only
    summary = pd.read_csv(out / "summary.csv").set_index("method")
    assert summary.loc["blobs", "frames"] == 2 and summary.loc["flic0", "frames"] == 3
    # the timed runs cluster as segment does (ground setting, each variant's own remover)
    seg = tmp_path / "seg"
    _ok(["segment", str(toy.recording), "--method", "blobs", "--config", str(toy.config),
         "--out", str(seg)])  # fmt: skip
    for _, row in frames[frames["method"] == "blobs"].iterrows():
        labels = np.load(seg / row["sequence"] / f"{row['frame']:06d}.npy")
        assert row["clusters"] == labels.max() > 0


def test_sweep_uses_the_declared_range_and_matches_evaluate(toy, tmp_path):
    out = tmp_path / "sweep"
    _ok(["sweep-threshold", str(toy.recording), "--method", "blobs", "--config",
         str(toy.config), "--out", str(out)])  # fmt: skip
    table = pd.read_csv(out / "sweep.csv")
    assert table["value"].tolist() == [20.0, 40.0]  # PixelBlobs.sweep_range
    assert (table["param"] == "max_range_m").all()
    # at 40 m (the config's value) the sweep scores what evaluate scores
    _ok(["evaluate", str(toy.recording), "--methods", "blobs", "--config", str(toy.config),
         "--setting", "no-ground", "--out", str(tmp_path / "ev")])  # fmt: skip
    ev = pd.read_csv(tmp_path / "ev" / "per_setting.csv").iloc[0]
    for key in ("iou_mu", "p_mu", "p_0.50", "objects"):
        assert table[key].iloc[1] == pytest.approx(ev[key], abs=1e-9), key
    assert 0 < table["objects"].iloc[1] and table["iou_mu"].iloc[1] > 0


def test_a_missing_optional_package_fails_only_when_used(toy, tmp_path):
    registry.register(
        "format",
        "toy",
        registry.Entry(f"{__name__}:ToyFormat", "toy", requires="no_such_package_xyz",
                       install="pip install no-such-package-xyz"),
        replace=True,
    )  # fmt: skip
    import flic_cli.io  # noqa: F401  (still imports)

    result = runner.invoke(app, ["segment", str(toy.recording), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "no_such_package_xyz" in result.output and "pip install no-such-pack" in result.output
    assert "Traceback" not in result.output
    # other formats are unaffected
    _ok(["segment", str(toy.kitti), "--method", "flic0", "--out", str(tmp_path / "k")])
