"""The measuring scripts behind results/ still load against the package: every script imports,
and each study's subcommands build their parsers (``--help``). A renamed or removed function of
flic_cli that a script uses fails here, not in the next ``scripts/make_results.sh`` run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
STUDIES = {
    "ground_study.py": ("table", "speed", "sweep", "oracle", "losses", "heights", "figure"),
    "sensors_study.py": ("profiles", "links", "ground-column", "mc-degrees", "recordings"),
    "peers_study.py": ("clusterers", "ref-diff", "euclidean", "ablation"),
}


def _help(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, *args, "--help"], capture_output=True, text=True, cwd=SCRIPTS.parent
    )


@pytest.mark.slow
@pytest.mark.parametrize("script", sorted(STUDIES))
def test_every_study_subcommand_builds_its_parser(script: str) -> None:
    top = _help(str(SCRIPTS / script))
    assert top.returncode == 0, top.stderr
    for sub in STUDIES[script]:
        assert sub in top.stdout
        res = _help(str(SCRIPTS / script), sub)
        assert res.returncode == 0, f"{script} {sub}: {res.stderr}"
        assert res.stdout.startswith(f"usage: {script} {sub}")


def test_the_studies_listed_here_are_the_ones_in_scripts() -> None:
    assert set(STUDIES) == {p.name for p in SCRIPTS.glob("*_study.py")}
