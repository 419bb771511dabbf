"""Frame loads of two flic trees, alternated: this checkout against another (e.g. main).

    git archive main flic_cli | tar -x -C /tmp/main-tree
    python scripts/sensors/read_ab.py --other /tmp/main-tree --rounds 3 --repeat 400

Each round runs one process per tree (this checkout's flic_cli and the other's, put first on
PYTHONPATH), pinned to one core, that opens each recording, loads its frame once (warm-up) and
then ``--repeat`` times, printing min / p10 / median ms of a load (and, in brackets, the
minimum of ``--opens`` opens, ms). Alternating whole processes is how two
versions of one module are compared here: on a loaded machine the minimum of each is the figure
to compare, and the rounds show how much it moves.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

from recordings import ROOT, SENSORS  # scripts/sensors/recordings.py

CHILD = """
import json, os, sys, time
import numpy as np
os.sched_setaffinity(0, {int(sys.argv[2])})
import flic_cli
from flic_cli.io import open_dataset
out = {"tree": flic_cli.__file__}
for path, repeat in json.loads(sys.argv[1]):
    opens = []
    for _ in range(int(sys.argv[3])):
        t = time.perf_counter()
        ds = open_dataset(path)
        opens.append(time.perf_counter() - t)
    ref = ds.refs()[0]
    ds.load(ref)
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        ds.load(ref)
        ts.append(time.perf_counter() - t)
    out[path] = [round(1e3 * float(v), 3) for v in (np.min(ts), np.percentile(ts, 10),
                                                    np.median(ts), np.min(opens))]
print(json.dumps(out))
"""

DEFAULT = [
    "velodyne/vlp16_velodyne_example.pcap",
    "pcd/robosense_helios16p_1691031766781547066.pcd",
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", type=Path, required=True, help="a folder holding flic_cli/")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=400, help="loads per recording (ASCII: /10)")
    parser.add_argument("--core", type=int, default=0)
    parser.add_argument("--opens", type=int, default=5, help="opens per recording and round")
    parser.add_argument("--recordings", nargs="*", default=DEFAULT)
    args = parser.parse_args()
    jobs = [
        (str(SENSORS / r), args.repeat // 10 if r.endswith(".pcd") else args.repeat)
        for r in args.recordings
    ]
    for k in range(args.rounds):
        for tree in (args.other.resolve(), ROOT):
            env = {**os.environ, "PYTHONPATH": str(tree)}
            res = subprocess.run(
                [sys.executable, "-c", CHILD, json.dumps(jobs), str(args.core), str(args.opens)],
                env=env, cwd=tree, capture_output=True, text=True, check=True,
            )  # fmt: skip
            out = json.loads(res.stdout)
            cells = [
                f"{Path(p).name[:24]} {v[0]:.3f} / {v[1]:.3f} / {v[2]:.3f} (open {v[3]:.1f})"
                for p, v in out.items()
                if p != "tree"
            ]
            print(f"round {k} {out['tree']}: " + " | ".join(cells), flush=True)


if __name__ == "__main__":
    main()
