"""ASCII PCD data sections parsed by each library option, interleaved on one core: which is
fastest, and which gives exactly pypcd4's numbers.

    python scripts/sensors/ascii_parsers.py --repeat 100 --core 1

On the Helios-16P recording (15,258 points, 10 fields) and the nuScenes sweep (34,688 points,
x y z intensity ring) written as an ASCII PCD by pypcd4, times the x, y, z parse (what a frame
load needs) of: flic's reader (``read_pcd(path, ("x", "y", "z"))``, pandas' C reader), pypcd4's
``PointCloud.from_path`` (``numpy.loadtxt`` of every field), ``numpy.loadtxt`` of x, y, z,
``numpy.fromstring(sep=" ")`` of the whole section, pandas ``read_csv(engine="c")`` of x, y, z
alone, and pyarrow's CSV reader (single-threaded) where pyarrow can be imported (it is no
dependency of flic). ``exact`` compares the x, y, z bytes with pypcd4's.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
from recordings import ROOT, SENSORS  # scripts/sensors/recordings.py

from flic_cli.io.pcd import _header_lines, read_pcd

HELIOS = "pcd/robosense_helios16p_1691031766781547066.pcd"
NUSCENES = "nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin"


def _nuscenes_ascii(folder: Path) -> Path:
    from pypcd4 import Encoding, PointCloud

    pts = np.fromfile(SENSORS / NUSCENES, dtype="<f4").reshape(-1, 5)
    cloud = PointCloud.from_points(
        [pts[:, 0], pts[:, 1], pts[:, 2], pts[:, 3], pts[:, 4].astype(np.uint16)],
        ("x", "y", "z", "intensity", "ring"),
        (np.float32, np.float32, np.float32, np.float32, np.uint16),
    )
    path = folder / "nuscenes_sweep_ascii.pcd"
    cloud.save(path, encoding=Encoding.ASCII)
    return path


def _parsers(path: Path) -> dict:
    """name -> function returning (N, 3) float32 x, y, z."""
    from pypcd4 import MetaData, PointCloud

    with open(path, "rb") as fp:
        meta = MetaData.parse_header(_header_lines(fp))
        start = fp.tell()
    fields = len(meta.fields)

    def data() -> bytes:
        with open(path, "rb") as f:
            f.seek(start)
            return f.read()

    def xyz(rec: np.ndarray) -> np.ndarray:
        return np.stack([rec["x"], rec["y"], rec["z"]], axis=1)

    def loadtxt() -> np.ndarray:
        with open(path, "rb") as f:
            f.seek(start)
            return np.loadtxt(f, np.float32, delimiter=" ", usecols=(0, 1, 2))

    def fromstring() -> np.ndarray:
        flat = np.fromstring(data(), dtype=np.float64, sep=" ")
        return flat.reshape(-1, fields)[:, :3].astype(np.float32)

    def pandas_c() -> np.ndarray:
        with open(path, "rb") as f:
            f.seek(start)
            frame = pd.read_csv(
                f, sep=" ", header=None, usecols=[0, 1, 2], dtype=np.float32, engine="c",
                nrows=meta.points,
            )  # fmt: skip
        return frame.to_numpy()

    out = {
        "flic read_pcd (pandas C, x y z)": lambda: xyz(read_pcd(path, ("x", "y", "z"))),
        "pypcd4 PointCloud.from_path (numpy.loadtxt, all fields)": lambda: xyz(
            PointCloud.from_path(path).pc_data
        ),
        "numpy.loadtxt (x y z)": loadtxt,
        "numpy.fromstring sep=' ' (all fields)": fromstring,
        "pandas.read_csv engine=c (x y z)": pandas_c,
    }
    try:
        import pyarrow as pa
        import pyarrow.csv as pcsv
    except ImportError:
        return out
    pa.set_cpu_count(1)
    pa.set_io_thread_count(1)
    names = [f"c{i}" for i in range(fields)]

    def arrow() -> np.ndarray:
        table = pcsv.read_csv(
            pa.py_buffer(data()),
            read_options=pcsv.ReadOptions(column_names=names, use_threads=False),
            parse_options=pcsv.ParseOptions(delimiter=" "),
            convert_options=pcsv.ConvertOptions(
                include_columns=names[:3], column_types=dict.fromkeys(names[:3], pa.float32())
            ),
        )
        return np.stack([table.column(i).to_numpy() for i in range(3)], axis=1)

    out[f"pyarrow {pa.__version__} csv (x y z; no flic dependency)"] = arrow
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=100)
    parser.add_argument("--core", type=int, default=1)
    parser.add_argument("--out", type=Path, default=ROOT / "results/sensors/ascii_parsers.csv")
    args = parser.parse_args()
    os.sched_setaffinity(0, {args.core})
    from pypcd4 import PointCloud

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        inputs = [
            ("Helios-16P PCD", SENSORS / HELIOS),
            ("nuScenes sweep as ASCII PCD", _nuscenes_ascii(Path(tmp))),
        ]
        for name, path in inputs:
            ref = PointCloud.from_path(path).pc_data
            ref = np.stack([ref["x"], ref["y"], ref["z"]], axis=1)
            funcs = _parsers(path)
            exact = {}
            for k, f in funcs.items():  # warm-up, and the exactness check
                got = f()
                exact[k] = got.dtype == ref.dtype and got.tobytes() == ref.tobytes()
            times: dict[str, list[float]] = {k: [] for k in funcs}
            for _ in range(args.repeat):  # interleaved: all see the same machine load
                for k, f in funcs.items():
                    t = time.perf_counter()
                    f()
                    times[k].append(time.perf_counter() - t)
            for k, ts in times.items():
                ms = 1e3 * np.asarray(ts)
                rows.append(
                    {
                        "input": name,
                        "points": ref.shape[0],
                        "bytes": path.stat().st_size,
                        "parser": k,
                        "exact": exact[k],
                        "ms_min": round(float(ms.min()), 3),
                        "ms_p10": round(float(np.percentile(ms, 10)), 3),
                        "ms_median": round(float(np.median(ms)), 3),
                        "load_average_1min": round(os.getloadavg()[0], 1),
                        "repeats": args.repeat,
                    }
                )
                print(rows[-1], flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(args.out, index=False)


if __name__ == "__main__":
    main()
