"""``flic benchmark`` of two git revisions on the same data, alternating, in one run.

Each revision gets a checkout and a virtual environment of its own, outside the repository, under
``--work`` (``git worktree add --detach`` and ``pip install -e``; an existing one is reused, and
``--checkout REV=DIR`` names a checkout with its ``.venv`` made elsewhere). Then, round by round,
each revision's ``flic benchmark --rounds 1`` runs on the same frames, pinned to one core
(``taskset -c CPU``, ``NUMBA_NUM_THREADS=1``, ``--threads 1``), the order alternating ABBA so
that a slow drift of the machine's load falls on both alike::

    python scripts/benchmark_revisions.py 3e00d28 main --data /tmp/log/moosmann \
        --frames 0:200 --rounds 6 --work /tmp/flic-revisions --out results/benchmark/revisions/x

Only the command line of each revision is used, so revisions whose Python API differs compare.
The methods: those asked for (default: the paper's and Bridge) that both revisions' ``flic
config`` define; ``read`` and ``project`` (the file reading and the projection, which
``flic benchmark`` times as stages of their own) are compared too.

Writes into ``--out``:

``ratios.csv``
    One row per method and stage: ``name, kind, frames, rounds, before_ms, after_ms`` (the median
    ms per frame over all timed frames and rounds), ``ratio`` (after / before), ``lo, hi`` (95 %
    bootstrap interval of the ratio that resamples rounds and frames together: both revisions'
    times of a round and frame are drawn as one, since they share the machine's state of that
    moment), ``round_min, round_max`` (the smallest and largest ratio of a single round),
    ``verdict`` (``slower`` when ``lo > 1``, ``faster`` when ``hi < 1``, else ``same``),
    ``min_ratio, min_lo, min_hi, verdict_min`` the same of each frame's fastest round (the
    median over frames of the minimum over rounds; frames resampled): other work only adds time,
    so on a loaded machine this is the steadier estimate,
    ``clusters_equal`` (share of the frames where both revisions found as many clusters) and
    ``config_equal`` (whether the method's section of ``flic config`` is the same text).
``ratios.png``
    The ratios with their intervals.
``frames.csv``
    Every timed call: ``revision, round, name, index, milliseconds, clusters``.
``run.json``
    The command, both revisions' commits, the machine (CPU, cores, load average before and after)
    and each revision's ``environment.json`` of its first round; ``config_diff.txt`` the unified
    diff of both revisions' ``flic config``.
"""

from __future__ import annotations

import argparse
import difflib
import json
import os
import platform
import re
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

#: The paper's methods and Bridge (``results/README.md`` section 3).
METHODS = "bogoslavskyi,flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan"
STAGES = ("read", "project")
REPO = Path(__file__).resolve().parents[1]


def sh(cmd: list[str], cwd: Path | None = None, env: dict[str, str] | None = None) -> str:
    """Run ``cmd``; its stdout. Exits with its stderr when it fails."""
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{shlex.join(cmd)} failed ({done.returncode}):\n{done.stderr[-4000:]}")
    return done.stdout


def commit_of(rev: str) -> str:
    """The full commit id of ``rev`` in this repository."""
    return sh(["git", "-C", str(REPO), "rev-parse", "--verify", f"{rev}^{{commit}}"]).strip()


def checkout(commit: str, work: Path, given: dict[str, Path]) -> Path:
    """A checkout of ``commit`` with its ``.venv``: given, or reused or made in ``work``."""
    for rev, path in given.items():
        if commit_of(rev) == commit:
            head = sh(["git", "-C", str(path), "rev-parse", "HEAD"]).strip()
            if head != commit:
                raise SystemExit(f"--checkout {rev}={path}: that checkout is at {head}")
            return path
    tree = work / commit[:12]
    if not (tree / ".git").exists():
        work.mkdir(parents=True, exist_ok=True)
        sh(["git", "-C", str(REPO), "worktree", "add", "--detach", str(tree), commit])
    if not (tree / ".venv" / "bin" / "flic").exists():
        print(f"installing {commit[:12]} into {tree}/.venv", file=sys.stderr)
        sh([sys.executable, "-m", "venv", str(tree / ".venv")])
        sh([str(tree / ".venv/bin/pip"), "install", "-q", "-e", str(tree)])
    return tree


def env_one_core() -> dict[str, str]:
    """The environment of a timed call: one thread for numba and the BLAS pools."""
    env = dict(os.environ)
    for k in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[k] = "1"
    env.pop("VIRTUAL_ENV", None)
    return env


def config_sections(tree: Path) -> tuple[str, dict[str, str]]:
    """``flic config`` of a checkout: the whole text and each ``[methods.NAME]`` section."""
    text = sh([str(tree / ".venv/bin/flic"), "config"], cwd=tree, env=env_one_core())
    sections: dict[str, str] = {}
    name = None
    for line in text.splitlines():
        m = re.match(r"^\[methods\.([^\]]+)\]$", line)
        if m:
            name = m.group(1)
            sections[name] = ""
        elif line.startswith("["):
            name = None
        elif name is not None:
            sections[name] += line + "\n"
    return text, {k: v.strip() for k, v in sections.items()}


def slow_option(tree: Path) -> str:
    """The revision's name of the option that samples slow methods every n-th frame."""
    help_text = sh([str(tree / ".venv/bin/flic"), "benchmark", "--help"], cwd=tree)
    return "--slow-every" if "--slow-every" in help_text else "--dbscan-every"


def bench(
    tree: Path, args: argparse.Namespace, methods: list[str], out: Path, frames: str | None
) -> pd.DataFrame:
    """One ``flic benchmark --rounds 1`` of a checkout, pinned to one core; its ``frames.csv``."""
    cmd = ["taskset", "-c", str(args.cpu), str(tree / ".venv/bin/flic"), "benchmark"]
    cmd += [str(args.data.resolve()), "--methods", ",".join(methods)]
    cmd += ["--frames", frames] if frames else []
    cmd += ["--rounds", "1", "--threads", "1", "--repeat", str(args.repeat)]
    cmd += ["--warmup", str(args.warmup), slow_option(tree), str(args.slow_every)]
    cmd += ["--no-plots", "--out", str(out)] + shlex.split(args.extra)
    sh(cmd, cwd=tree, env=env_one_core())
    return pd.read_csv(out / "frames.csv")


def bootstrap(
    before: np.ndarray, after: np.ndarray, n: int, rng: np.random.Generator
) -> tuple[float, float]:
    """95 % interval of median(after) / median(before), resampling rounds and frames together.

    ``before`` and ``after`` are (rounds, frames) arrays, NaN where a frame was not timed.
    """
    r, f = before.shape
    ratios = np.empty(n)
    for b in range(n):
        ri, fi = rng.integers(0, r, r), rng.integers(0, f, f)
        ratios[b] = np.nanmedian(after[np.ix_(ri, fi)]) / np.nanmedian(before[np.ix_(ri, fi)])
    lo, hi = np.nanpercentile(ratios, [2.5, 97.5])
    return float(lo), float(hi)


def compare(
    frames: pd.DataFrame,
    names: list[str],
    config_equal: dict[str, bool],
    n_boot: int,
    seed: int,
) -> pd.DataFrame:
    """The ``ratios.csv`` table of the ``frames.csv`` table."""
    rng = np.random.default_rng(seed)
    rows = []
    for name in names:
        sub = frames[frames["name"] == name]
        # only the (round, frame) pairs both revisions timed
        wide = sub.pivot_table(
            index=["round", "index"], columns="revision", values="milliseconds", aggfunc="first"
        ).dropna()
        clusters = sub.pivot_table(
            index=["round", "index"], columns="revision", values="clusters", aggfunc="first"
        ).dropna()
        b = wide["before"].unstack("index").to_numpy(dtype=float)
        a = wide["after"].unstack("index").to_numpy(dtype=float)
        per_round = np.nanmedian(a, axis=1) / np.nanmedian(b, axis=1)
        ratio = float(np.median(wide["after"]) / np.median(wide["before"]))
        lo, hi = bootstrap(b, a, n_boot, rng)
        verdict = "slower" if lo > 1 else "faster" if hi < 1 else "same"
        # each frame's fastest round: other work only ever adds time, so this is the estimate
        # least moved by the machine's load (frames resampled)
        fb, fa = np.nanmin(b, axis=0), np.nanmin(a, axis=0)
        min_ratio = float(np.median(fa) / np.median(fb))
        min_lo, min_hi = bootstrap(fb[None, :], fa[None, :], n_boot, rng)
        rows.append(
            {
                "name": name,
                "kind": "stage" if name in STAGES else "method",
                "frames": wide.index.get_level_values("index").nunique(),
                "rounds": wide.index.get_level_values("round").nunique(),
                "before_ms": float(np.median(wide["before"])),
                "after_ms": float(np.median(wide["after"])),
                "ratio": ratio,
                "lo": lo,
                "hi": hi,
                "round_min": float(per_round.min()),
                "round_max": float(per_round.max()),
                "verdict": verdict,
                "min_ratio": min_ratio,
                "min_lo": min_lo,
                "min_hi": min_hi,
                "verdict_min": "slower" if min_lo > 1 else "faster" if min_hi < 1 else "same",
                "clusters_equal": float((clusters["before"] == clusters["after"]).mean())
                if name not in STAGES
                else np.nan,
                "config_equal": config_equal.get(name, True),
            }
        )
    return pd.DataFrame(rows)


def plot(table: pd.DataFrame, title: str, path: Path) -> None:
    """The ratios with their intervals, one row per method and stage."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 0.5 * len(table) + 1.8))
    y = np.arange(len(table))[::-1].astype(float)
    colour = {"slower": "tab:red", "faster": "tab:green", "same": "tab:blue"}
    for col, lo, hi, verdict, dy, marker, label in (
        ("ratio", "lo", "hi", "verdict", 0.12, "o", "median over rounds and frames"),
        ("min_ratio", "min_lo", "min_hi", "verdict_min", -0.12, "D", "each frame's fastest round"),
    ):
        err = np.vstack([table[col] - table[lo], table[hi] - table[col]])
        ax.errorbar(table[col], y + dy, xerr=err, fmt="none", ecolor="0.45", capsize=3)
        ax.scatter(
            table[col],
            y + dy,
            c=[colour[v] for v in table[verdict]],
            marker=marker,
            zorder=3,
            label=label,
        )
    ax.scatter(table["round_min"], y + 0.12, marker="|", c="0.6", zorder=2, label="single rounds")
    ax.scatter(table["round_max"], y + 0.12, marker="|", c="0.6", zorder=2)
    ax.axvline(1.0, color="k", lw=0.8)
    ticks = [f"{n} ({b:.3g} ms)" for n, b in zip(table["name"], table["before_ms"], strict=True)]
    ax.set_yticks(y, ticks)
    ax.set_xlabel("time after / before, 95 % interval (red: slower, green: faster)")
    ax.set_title(title, fontsize=8)
    from matplotlib.lines import Line2D  # legend proxies: the markers' colours are the verdicts

    proxies = [
        Line2D([], [], ls="", marker=m, color="0.3", label=lab)
        for m, lab in (("o", "median over rounds and frames"), ("D", "each frame's fastest round"))
    ]
    proxies.append(Line2D([], [], ls="", marker="|", color="0.6", label="single rounds"))
    ax.legend(handles=proxies, loc="lower right", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def machine() -> dict[str, object]:
    """CPU model, cores and the load average now."""
    cpu = platform.processor()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "loadavg": list(os.getloadavg())}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("before", help="the earlier revision (any git revision)")
    p.add_argument("after", help="the later revision")
    p.add_argument("--data", type=Path, required=True, help="the data flic benchmark reads")
    p.add_argument("--frames", default=None, help="flic benchmark --frames (default: all)")
    p.add_argument("--methods", default=METHODS, help=f"comma-separated (default {METHODS})")
    p.add_argument("--rounds", type=int, default=6, help="rounds per revision (default 6)")
    p.add_argument("--repeat", type=int, default=1, help="flic benchmark --repeat (default 1)")
    p.add_argument("--warmup", type=int, default=3, help="flic benchmark --warmup (default 3)")
    p.add_argument("--slow-every", type=int, default=10, help="slow methods' every n-th frame")
    p.add_argument("--cpu", type=int, default=0, help="the core both revisions run on")
    p.add_argument("--extra", default="", help="more flic benchmark options, one string")
    p.add_argument("--work", type=Path, required=True, help="checkouts and venvs (reused)")
    p.add_argument(
        "--checkout",
        action="append",
        default=[],
        metavar="REV=DIR",
        help="use this existing checkout (with its .venv) for REV",
    )
    p.add_argument("--bootstrap", type=int, default=2000, help="bootstrap resamples")
    p.add_argument(
        "--tables-only",
        action="store_true",
        help="time nothing: remake ratios.csv and ratios.png from OUT/frames.csv",
    )
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args()

    given = {}
    for item in args.checkout:
        rev, _, path = item.partition("=")
        given[rev] = Path(path).resolve()
    commits = {"before": commit_of(args.before), "after": commit_of(args.after)}
    if commits["before"] == commits["after"]:
        print("note: both revisions are the same commit (an A/A control)", file=sys.stderr)
    trees = {k: checkout(c, args.work.resolve(), given) for k, c in commits.items()}
    configs = {k: config_sections(t) for k, t in trees.items()}
    both = set(configs["before"][1]) & set(configs["after"][1])
    asked = [m for m in args.methods.split(",") if m]
    methods = [m for m in asked if m in both]
    if set(asked) - set(methods):
        print(
            f"not in both revisions, left out: {sorted(set(asked) - set(methods))}", file=sys.stderr
        )
    config_equal = {m: configs["before"][1][m] == configs["after"][1][m] for m in methods}
    args.out.mkdir(parents=True, exist_ok=True)
    diff = difflib.unified_diff(
        configs["before"][0].splitlines(True),
        configs["after"][0].splitlines(True),
        f"flic config @ {commits['before'][:12]}",
        f"flic config @ {commits['after'][:12]}",
    )
    (args.out / "config_diff.txt").write_text("".join(diff))

    if args.tables_only:
        frames = pd.read_csv(args.out / "frames.csv")
        table = compare(frames, methods + list(STAGES), config_equal, args.bootstrap, seed=0)
        table.to_csv(args.out / "ratios.csv", index=False, float_format="%.4g")
        run = json.loads((args.out / "run.json").read_text())
        plot(table, run["title"], args.out / "ratios.png")
        print(table.to_string(index=False))
        return
    start = {"time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **machine()}
    parts, envs = [], {}
    with tempfile.TemporaryDirectory(prefix="flic-revisions-") as tmp:
        # compile both revisions' numba kernels (cached per checkout) before anything is timed
        for k, t in trees.items():
            bench(t, args, methods, Path(tmp) / f"compile-{k}", "0:1")
        for r in range(args.rounds):
            order = ("before", "after") if r % 4 in (0, 3) else ("after", "before")  # ABBA
            for k in order:
                t0 = time.monotonic()
                df = bench(trees[k], args, methods, Path(tmp) / f"{k}-{r}", args.frames)
                if r == 0:
                    envs[k] = json.loads((Path(tmp) / f"{k}-{r}" / "environment.json").read_text())
                df = df.rename(columns={"method": "name"})
                df.insert(0, "round", r)
                df.insert(0, "revision", k)
                parts.append(df[["revision", "round", "name", "index", "milliseconds", "clusters"]])
                print(
                    f"round {r + 1}/{args.rounds} {k}: {time.monotonic() - t0:.0f} s",
                    file=sys.stderr,
                )
    frames = pd.concat(parts, ignore_index=True)
    frames.to_csv(args.out / "frames.csv", index=False)
    table = compare(frames, methods + list(STAGES), config_equal, args.bootstrap, seed=0)
    table.to_csv(args.out / "ratios.csv", index=False, float_format="%.4g")
    title = (
        f"{commits['after'][:7]} / {commits['before'][:7]}, {args.data.name}, {args.rounds} rounds"
        f" alternating ABBA, one core\n({start['cpu']}, {start['cores']} cores, load average"
        f" {start['loadavg'][0]:.1f} at the start)"
    )
    plot(table, title, args.out / "ratios.png")
    run = {
        "command": shlex.join([sys.executable.rsplit("/", 1)[-1], *sys.argv]),
        "commits": commits,
        "checkouts": {k: str(t) for k, t in trees.items()},
        "methods": methods,
        "title": title,
        "start": start,
        "end": {"time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **machine()},
        "environment": envs,
    }
    (args.out / "run.json").write_text(json.dumps(run, indent=2) + "\n")
    print(table.to_string(index=False))


if __name__ == "__main__":
    main()
