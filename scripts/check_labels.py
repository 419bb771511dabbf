"""Fingerprint every method's labels through the command line, to show a change leaves them alone.

Runs ``flic segment`` for every method variant in every setting on the given datasets and writes
one row per prediction file: ``dataset, method, setting, remover, semantics, file, sha256``. Only
the command line is used, so the same script checks two revisions whose Python API differs::

    python scripts/check_labels.py --shared ../shared/data/semantickitti \
        --out results/labels/fingerprint.csv
    python scripts/check_labels.py --shared ../shared/data/semantickitti \
        --compare results/labels/fingerprint.csv

``--compare`` recomputes and exits 1, listing the differing files, when any hash differs. The
datasets: the shared SemanticKITTI frames (no-ground, ground with each method's own remover and
with the paper's, and oracle semantics) and the built-in synthetic sample (``flic sample``, 10
frames: its SemanticKITTI sequence the same way, its Moosmann log in the ground setting).
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

METHODS = (
    "bogoslavskyi", "flic0", "flic1", "flic6", "flic14", "flic1n", "flic6n", "flic14n",
    "bridge", "dbscan", "flic0-scipy",
)  # fmt: skip
COLUMNS = ("dataset", "method", "setting", "remover", "semantics", "file", "sha256")


def runs(datasets: dict[str, tuple[Path, bool]]) -> list[tuple[str, str, str, str, str]]:
    """(dataset, method, setting, remover, semantics) of every ``flic segment`` call."""
    out = []
    for name, (_, labelled) in datasets.items():
        for m in METHODS:
            if labelled:
                out.append((name, m, "no-ground", "-", "none"))
                out.append((name, m, "ground", "-", "oracle"))
            out.append((name, m, "ground", "own", "none"))
            out.append((name, m, "ground", "paper", "none"))
    return out


def segment(flic: str, data: Path, run: tuple[str, ...], out: Path) -> list[tuple[str, str]]:
    """Run one ``flic segment``; (relative file, sha256) of every prediction it wrote."""
    _, method, setting, remover, semantics = run
    cmd = [flic, "segment", str(data), "--method", method, "--setting", setting, "--out", str(out)]
    if remover != "-":
        cmd += ["--ground-remover", remover]
    if semantics != "none":
        cmd += ["--semantics", semantics]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed:\n{done.stderr}")
    files = sorted(p for p in out.rglob("*") if p.is_file() and p.name.endswith((".label", ".png")))
    return [(str(p.relative_to(out)), hashlib.sha256(p.read_bytes()).hexdigest()) for p in files]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shared", type=Path, help="the shared SemanticKITTI root")
    parser.add_argument("--out", type=Path, help="write the fingerprint CSV here")
    parser.add_argument("--compare", type=Path, help="compare with this fingerprint CSV")
    parser.add_argument("--flic", default="flic", help="the flic executable")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run([args.flic, "sample", str(tmp / "sample"), "--frames", "10"], check=True,
                       capture_output=True)  # fmt: skip
        datasets = {
            "sample-semantickitti": (tmp / "sample" / "semantickitti", True),
            "sample-moosmann": (tmp / "sample" / "moosmann", False),
        }
        if args.shared is not None:
            datasets["shared"] = (args.shared, True)
        todo = runs(datasets)

        def one(k: int) -> list[tuple]:
            run = todo[k]
            files = segment(args.flic, datasets[run[0]][0], run, tmp / f"out{k}")
            return [(*run, f, h) for f, h in files]

        with ThreadPoolExecutor(args.workers) as pool:
            rows = [r for part in pool.map(one, range(len(todo))) for r in part]
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        with open(args.out, "w", newline="") as f:
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(COLUMNS)
            writer.writerows(rows)
        print(f"{len(rows)} prediction files from {len(todo)} runs -> {args.out}")
    if args.compare is not None:
        with open(args.compare, newline="") as f:
            before = {tuple(r[:6]): r[6] for r in csv.reader(f) if r[0] != "dataset"}
        now = {tuple(r[:6]): r[6] for r in rows}
        differ = sorted(k for k in before.keys() | now.keys() if before.get(k) != now.get(k))
        for k in differ[:20]:
            print("differs:", *k)
        print(f"{len(now)} files compared with {args.compare}: {len(differ)} differ")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
