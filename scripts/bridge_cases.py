"""Bridge's weak cases as a labelled SemanticKITTI folder: people beside people, poles and walls
at several ranges and spacings, and box-shaped vehicles whose faces lie far apart in range.

Every frame holds one *case* at one range: several copies of the same arrangement spread over
azimuths 30 deg apart (no copy hides another), on a flat road, the HDL-64E model of
:mod:`flic_cli.sample` with its noise (dropouts, range noise; seeded per frame). The cases:

- ``people-side-S``: two people side by side across the line of sight, a gap of S metres between
  their boxes (0.5 x 0.4 x 1.75 m each);
- ``people-depth-S``: one person S metres behind the other along the line of sight, 0.3 m to the
  side, so that each shows part of its width;
- ``people-group-S``: four people in a row across the line of sight, S metres apart;
- ``person-pole-S``: a person and a pole (r = 0.06 m, 3 m high) S metres beside it;
- ``person-wall-S``: a person S metres in front of a wall (building, 4 m wide, 3 m high);
- ``car-rear``: a car (:func:`flic_cli.sample.car`) seen from behind: rear face, trunk lid, roof;
- ``van-front``: a van seen from the front, a box with a hood: a 1.0 m high, 0.7 m long hood box
  before a 2.1 m high cabin box (its face 0.7 m behind the hood's), other-vehicle;
- ``box-pair-S``: van-front cut in two, the cabin box S metres behind the hood box: two objects
  whose nearest returns lie as far apart, at the same height, as van-front's two faces;
- ``truck-front``: a truck seen from the front, a 2.6 m high cab and a 3.4 m high cargo box
  whose face stands 0.5 m behind the cab's back (2.2 m behind the cab's face), truck.

Usage::

    python scripts/bridge_cases.py OUT            # writes OUT/sequences/00 and OUT/cases.csv
    flic evaluate OUT --methods bridge,flic0,bogoslavskyi --setting no-ground --out EVAL
    python scripts/bridge_cases.py OUT --table EVAL --dest DEST  # IoU per case, range, method

``cases.csv``: frame, case, range_m, spacing_m, instance, class of every object.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from flic_cli.io.semantickitti import write_bin, write_calib, write_label, write_poses, write_times
from flic_cli.sample import Box, Cylinder, Ground, car, custom_scene, person, render_kitti

PERSON, CAR, TRUCK, OTHER_VEHICLE, BUILDING, POLE = 30, 10, 18, 20, 50, 80
RANGES_M = (8.0, 12.0, 16.0, 20.0, 25.0, 30.0)
SPACINGS_M = (0.3, 0.5, 0.8)
AZIMUTHS_DEG = (-75.0, -45.0, -15.0, 15.0, 45.0, 75.0, 105.0, 135.0, 165.0, -165.0, -135.0, -105.0)
CALIB = {"Tr": np.eye(3, 4)}


def _at(rng: float, az: float, along: float, across: float) -> tuple[float, float]:
    """(x, y) of a point ``along`` metres beyond range ``rng`` on azimuth ``az`` (rad) and
    ``across`` metres to its left."""
    c, s = np.cos(az), np.sin(az)
    return (rng + along) * c - across * s, (rng + along) * s + across * c


def _box(x: float, y: float, z0: float, size: tuple, yaw: float, sem: int, inst: int) -> Box:
    """A box standing at height ``z0`` (sensor frame), footprint centre (x, y)."""
    sx, sy, sz = size
    return Box((x, y, z0 + sz / 2), (sx / 2, sy / 2, sz / 2), yaw, sem, inst)


def arrangement(case: str, spacing: float, rng: float, az: float, first: int) -> tuple[list, list]:
    """The primitives (boxes, cylinders) of one copy of ``case`` at range ``rng``, azimuth
    ``az`` (rad); instance ids from ``first`` on."""
    zg = -Ground.flat().sensor_height
    boxes: list = []
    cyls: list = []
    yaw = float(az)
    if case == "people-side":
        for i, across in enumerate((-(spacing + 0.4) / 2, (spacing + 0.4) / 2)):
            boxes.append(person(*_at(rng, az, 0.0, across), first + i, yaw=yaw))
    elif case == "people-depth":
        boxes.append(person(*_at(rng, az, 0.0, 0.0), first, yaw=yaw))
        boxes.append(person(*_at(rng, az, spacing + 0.5, 0.3), first + 1, yaw=yaw))
    elif case == "people-group":
        for i in range(4):
            across = (i - 1.5) * (spacing + 0.4)
            boxes.append(person(*_at(rng, az, 0.0, across), first + i, yaw=yaw))
    elif case == "person-pole":
        boxes.append(person(*_at(rng, az, 0.0, 0.0), first, yaw=yaw))
        x, y = _at(rng, az, 0.0, 0.2 + spacing + 0.06)
        cyls.append(Cylinder((x, y), 0.06, zg, zg + 3.0, POLE, 0))
    elif case == "person-wall":
        boxes.append(person(*_at(rng, az, 0.0, 0.0), first, yaw=yaw))
        x, y = _at(rng, az, 0.25 + spacing + 0.1, 0.0)
        boxes.append(_box(x, y, zg, (0.2, 4.0, 3.0), yaw, BUILDING, 0))
    elif case == "car-rear":
        boxes.extend(car(*_at(rng, az, 2.2, 0.0), first, yaw=yaw))
    elif case == "van-front":
        x, y = _at(rng, az, 0.35, 0.0)
        boxes.append(_box(x, y, zg + 0.25, (0.7, 1.9, 0.75), yaw, OTHER_VEHICLE, first))
        x, y = _at(rng, az, 0.7 + 1.9, 0.0)
        boxes.append(_box(x, y, zg + 0.25, (3.8, 1.9, 1.85), yaw, OTHER_VEHICLE, first))
    elif case == "box-pair":
        # van-front cut in two: the hood box and, ``spacing`` metres behind it, the cabin box,
        # two objects (a low trailer before a van): the hood's last row and the cabin's face
        # are as far apart as in van-front (plus the gap), at the same height
        x, y = _at(rng, az, 0.35, 0.0)
        boxes.append(_box(x, y, zg + 0.25, (0.7, 1.9, 0.75), yaw, OTHER_VEHICLE, first))
        x, y = _at(rng, az, 0.7 + spacing + 1.9, 0.0)
        boxes.append(_box(x, y, zg + 0.25, (3.8, 1.9, 1.85), yaw, OTHER_VEHICLE, first + 1))
    elif case == "truck-front":
        x, y = _at(rng, az, 0.85, 0.0)
        boxes.append(_box(x, y, zg + 0.4, (1.7, 2.4, 2.2), yaw, TRUCK, first))
        x, y = _at(rng, az, 2.2 + 3.0, 0.0)
        boxes.append(_box(x, y, zg + 0.5, (6.0, 2.5, 2.9), yaw, TRUCK, first))
    else:
        raise ValueError(case)
    return boxes, cyls


def cases() -> list[tuple[str, float]]:
    """(case, spacing) of every case, spacing 0 for the vehicles."""
    spaced = ("people-side", "people-depth", "people-group", "person-pole", "person-wall")
    return [(c, s) for c in spaced for s in SPACINGS_M] + [
        ("car-rear", 0.0),
        ("van-front", 0.0),
        ("truck-front", 0.0),
        ("box-pair", 0.3),
        ("box-pair", 0.5),
    ]


def write(out: Path, width: int, backdrop: float) -> None:
    """Render every case at every range into ``out/sequences/00``, list objects in cases.csv."""
    seq = out / "sequences" / "00"
    rows = []
    frame = 0
    for case, spacing in cases():
        for rng in RANGES_M:
            boxes, cyls, inst = [], [], 1
            # copies too close for their azimuths to hold them apart are left out
            n_copies = 12 if rng >= 12 else 6
            for az_deg in AZIMUTHS_DEG[:: 12 // n_copies]:
                b, c = arrangement(case, spacing, rng, np.radians(az_deg), inst)
                ids = sorted({p.instance for p in b + c if p.instance})
                for i in ids:
                    sem = next(p.semantic for p in b + c if p.instance == i)
                    rows.append([frame, case, rng, spacing, i, sem])
                inst = max(ids) + 1
                boxes += b
                cyls += c
            # walls all around (a square, ``backdrop`` metres from the sensor) give every ring
            # returns, so that the reader recovers the 64 rings from the scan order; without
            # them (backdrop 0) the rays past the objects see nothing (sky) and the reader falls
            # back to a spherical projection
            if backdrop > 0:
                for yaw in (0.0, np.pi / 2, np.pi, 3 * np.pi / 2):
                    x, y = backdrop * np.cos(yaw), backdrop * np.sin(yaw)
                    size = (1.0, 2.2 * backdrop, 80.0)
                    boxes.append(_box(x, y, -2.0, size, yaw, BUILDING, 0))
            scene = custom_scene(*boxes, *cyls)
            pts, labels = render_kitti(
                scene, width=width, noise=True, rng=np.random.default_rng(frame)
            )
            write_bin(seq / "velodyne" / f"{frame:06d}.bin", pts)
            write_label(seq / "labels" / f"{frame:06d}.label", labels)
            frame += 1
    write_calib(seq / "calib.txt", CALIB, float_format=".6e")
    write_poses(seq / "poses.txt", np.tile(np.eye(3, 4), (frame, 1, 1)), float_format=".6e")
    write_times(seq / "times.txt", np.arange(frame) / 10.0)
    with open(out / "cases.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "case", "range_m", "spacing_m", "instance", "semantic"])
        w.writerows(rows)
    print(f"{frame} frames, {len(rows)} objects -> {out}")


def table(out: Path, evaluation: Path, dest: Path | None) -> None:
    """Mean IoU (%) per case, spacing, range and method from EVAL/per_object.csv, printed and
    written to DEST/cases_iou.csv with a plot DEST/cases_iou.png (DEST default: EVAL)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd

    dest = evaluation if dest is None else dest
    dest.mkdir(parents=True, exist_ok=True)
    objs = pd.read_csv(out / "cases.csv")
    per = pd.read_csv(evaluation / "per_object.csv")
    per = per[per["setting"] == "no-ground"]
    m = per.merge(objs, on=["frame", "instance"], how="inner")
    t = m.pivot_table(
        index=["case", "spacing_m", "range_m"], columns="method", values="iou", aggfunc="mean"
    )
    t = (100 * t).round(1)
    t.to_csv(dest / "cases_iou.csv")
    print(t.to_string())
    names = list(dict.fromkeys(c for c, _ in cases()))
    fig, axes = plt.subplots(2, (len(names) + 1) // 2, figsize=(18, 7), sharey=True)
    styles = {0.0: "-", 0.3: ":", 0.5: "-", 0.8: "--"}
    for ax, name in zip(axes.flat, names, strict=False):
        sub = t.loc[name]
        for j, method in enumerate(t.columns):
            for spacing in sub.index.get_level_values(0).unique():
                line = sub.loc[spacing, method]
                label = method if spacing in (0.0, 0.5) or len(sub.index.levels[0]) == 1 else None
                ax.plot(line.index, line.values, styles.get(spacing, "-"), color=f"C{j}",
                        marker="o", ms=3, label=label)  # fmt: skip
        words = {0.3: "dotted", 0.5: "solid", 0.8: "dashed"}
        gaps = [g for g in sub.index.get_level_values(0).unique() if g]
        legend = ", ".join(f"{g:g} m {words.get(g, '')}" for g in gaps)
        ax.set_title(name + (f" (gap {legend})" if gaps else ""), fontsize=8)
        ax.set_xlabel("range (m)")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(names) :]:
        ax.axis("off")
    axes.flat[0].set_ylabel("mean IoU (%)")
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("Bridge's weak cases: mean IoU per object (no-ground setting)")
    fig.tight_layout()
    fig.savefig(dest / "cases_iou.png", dpi=110)
    print(f"wrote {dest / 'cases_iou.csv'} and {dest / 'cases_iou.png'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="output folder (a SemanticKITTI root)")
    ap.add_argument("--width", type=int, default=2048, help="columns per ring")
    ap.add_argument("--backdrop", type=float, default=40.0, help="walls this far, m (0: none)")
    ap.add_argument("--table", type=Path, help="a flic evaluate folder of OUT: print the table")
    ap.add_argument("--dest", type=Path, help="where --table writes cases_iou.csv / .png")
    a = ap.parse_args()
    if a.table:
        table(a.out, a.table, a.dest)
    else:
        write(a.out, a.width, a.backdrop)


if __name__ == "__main__":
    main()
