"""`flic config` prints the effective configuration as TOML that reads back to the same one."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # Python 3.10: the backport the project depends on there
    import tomli as tomllib

from flic_cli.cli import main
from flic_cli.config import load_config


def test_flic_config_prints_toml_that_loads_back_to_the_same_config(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["config"])
    out = capsys.readouterr().out
    assert exit_.value.code == 0
    printed = tomllib.loads(out)  # valid TOML (no null: unset parameters are left out)
    assert set(printed["methods"]) == set(load_config(None).methods)
    path = tmp_path / "effective.toml"
    path.write_text(out)
    assert load_config(path).as_dict() == load_config(None).as_dict()


PRESETS = sorted((Path(__file__).resolve().parents[1] / "configs").glob("*.toml"))


@pytest.mark.parametrize("path", PRESETS, ids=[p.name for p in PRESETS])
def test_every_shipped_config_loads_and_builds_the_variants_its_commands_name(path: Path) -> None:
    """The configs under configs/ (the ones results/ cite) load, every variant they define
    builds in both settings, and every name their comments' ``--methods`` lists is a variant."""
    import re

    from flic_cli.runs.pipeline import OWN, build_segmenter

    config = load_config(path)
    defined = set(tomllib.loads(path.read_text()).get("methods", {}))
    for name in defined:
        for setting in ("no-ground", "ground"):
            assert build_segmenter(config, name, setting, OWN).name == name
    named = {
        n
        for listing in re.findall(r"--methods[ =]([\w,.-]+)", path.read_text())
        for n in listing.split(",")
        if n and n != "..."
    }
    assert named <= set(config.methods), named - set(config.methods)
