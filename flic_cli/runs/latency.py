"""Latency per revolution on recordings (bags, pcaps): does a method keep up with the sensor?

A recording is processed as a stream: every revolution is decoded when it arrives, projected,
ground-extracted and clustered before the next one is read (one process, frames in recording
order). The latency of a revolution is the sum of those stages, measured per stage:

- ``decode``: reading the revolution from the file (message deserialisation, packet decoding,
  the sensor's range image where the decoder makes it);
- ``project``: the range image (:func:`flic_cli.runs.pipeline.prepare`);
- ``method``: ground extraction + clustering (``segmenter(image, points)``).

A method keeps up with a sensor turning at ``f`` Hz when the p99 latency stays below ``1000 / f``
ms (10 Hz: 100 ms, 20 Hz: 50 ms). The first revolution (JIT compilation, first imports) is
reported apart and left out of the statistics.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from flic_cli.io.base import FrameRef
from flic_cli.projection import Projection
from flic_cli.runs.pipeline import Segmenter, prepare

#: Formats whose frames are revolutions of a recording.
STREAMS = ("bag", "pcap", "ouster", "velodyne")
#: Sensor rates the latency is compared with, Hz.
RATES_HZ = (10, 20)
COLUMNS = ["method", "index", "sequence", "frame", "decode_ms", "project_ms", "method_ms",
           "total_ms", "points"]  # fmt: skip


@dataclass(frozen=True)
class LatencyJob:
    """One revolution through decode + range image + ground + clustering, each stage timed."""

    dataset: Any
    segmenter: Segmenter
    setting: str
    projection: Projection
    index: dict[FrameRef, int]

    def __call__(self, ref: FrameRef) -> tuple:
        t0 = time.perf_counter_ns()
        frame = self.dataset.load(ref)
        t1 = time.perf_counter_ns()
        prep = prepare(frame, self.setting, self.projection)
        t2 = time.perf_counter_ns()
        self.segmenter(prep.image, prep.points)
        t3 = time.perf_counter_ns()
        return (
            self.segmenter.name, self.index[ref], ref.sequence, ref.frame,
            (t1 - t0) / 1e6, (t2 - t1) / 1e6, (t3 - t2) / 1e6, (t3 - t0) / 1e6,
            int(prep.points.shape[0]),
        )  # fmt: skip


def measure(
    dataset: Any,
    refs: list[FrameRef],
    segmenters: list[Segmenter],
    setting: str,
    projection: Projection,
    progress: bool = True,
) -> pd.DataFrame:
    """Every method's per-revolution latency over ``refs`` (one pass per method, frames in
    order, as they arrive); the :data:`COLUMNS` table."""
    from flic_cli.runs.frames import FrameLoop

    index = {r: k for k, r in enumerate(refs)}
    rows = []
    for seg in segmenters:
        job = LatencyJob(dataset, seg, setting, projection, index)
        loop = FrameLoop(job, refs, desc=f"latency {seg.name}", progress=progress)
        rows += [row for _, row in loop]
    return pd.DataFrame(rows, columns=COLUMNS)


def summary_line(
    name: str, total_ms: np.ndarray, parts: dict[str, np.ndarray] | None = None
) -> str:
    """``NAME: latency per revolution over N frames after the first (F ms): median .. ms, p99 ..
    ms, max .. ms [(decode .., project .., method .. ms median)]; p99 keeps up with 10 Hz (100
    ms): yes, 20 Hz (50 ms): no``."""
    total = np.asarray(total_ms, dtype=np.float64)
    if total.size < 2:
        shown = f"{total[0]:.0f} ms" if total.size else "none"
        return (
            f"{name}: latency of the only revolution {shown} (JIT and cache loading included): "
            "too few revolutions to tell whether it keeps up with the sensor"
        )
    first = float(total[0])
    rest = total[1:]
    med, p99 = float(np.median(rest)), float(np.percentile(rest, 99))
    text = (
        f"{name}: latency per revolution (decode + range image + ground + cluster) over "
        f"{rest.size} frames after the first ({first:.0f} ms, JIT and cache loading included): "
        f"median {med:.1f} ms, p99 {p99:.1f} ms, max {rest.max():.1f} ms"
    )
    if parts:
        text += (
            " (median "
            + ", ".join(
                f"{k} {float(np.median(v[1:] if v.size > 1 else v)):.1f}" for k, v in parts.items()
            )
            + " ms)"
        )
    rates = ", ".join(
        f"{hz} Hz ({1000 / hz:.0f} ms): {'yes' if p99 <= 1000 / hz else 'no'}" for hz in RATES_HZ
    )
    return f"{text}; p99 keeps up with {rates}"


def report(table: pd.DataFrame) -> list[str]:
    """One :func:`summary_line` per method of a :func:`measure` table."""
    lines = []
    for name, sub in table.groupby("method", sort=False):
        sub = sub.sort_values("index")
        parts = {k: sub[f"{k}_ms"].to_numpy() for k in ("decode", "project", "method")}
        lines.append(summary_line(str(name), sub["total_ms"].to_numpy(), parts))
    return lines
