"""The measuring scripts behind results/ still load against the package: every script imports,
and each study's subcommands build their parsers (``--help``). A renamed or removed function of
flic_cli that a script uses fails here, not in the next ``scripts/make_results.sh`` run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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


def _bridge_deck():
    """``scripts/bridge_deck.py`` as the module ``bridge_deck`` (a measurement of a rule that is
    not built), loaded once."""
    import importlib.util

    if "bridge_deck" not in sys.modules:
        spec = importlib.util.spec_from_file_location("bridge_deck", SCRIPTS / "bridge_deck.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["bridge_deck"] = module  # the dataclass looks its module up
        spec.loader.exec_module(module)
    return sys.modules["bridge_deck"]


def _deck_column(step_m: float, above_x: float | None = None, columns: int = 1, width: int = 64):
    """Four rows, ``columns`` equal columns of ``width``: a low upright face 12 m away (rows 2, 3:
    p and the node below it) and an upright face ``step_m`` behind it (rows 0, 1: the node above
    q and q), or, with ``above_x``, the node above q at that horizontal range instead."""
    import numpy as np

    elevation = np.radians([-0.6, -1.0, -1.4, -1.8])
    x = np.array([12.0 + step_m if above_x is None else above_x, 12.0 + step_m, 12.0, 12.0])
    ranges = np.zeros((4, width), np.float32)
    ranges[:, :columns] = (x / np.cos(elevation))[:, None]
    return ranges, elevation


def test_deck_links_are_the_hand_found_pairs() -> None:
    import numpy as np

    deck = _bridge_deck().deck_links
    ranges, elevation = _deck_column(0.7)
    p, q = deck(ranges, elevation, None, 0.8)
    np.testing.assert_array_equal(p, [2 * 64])  # row 2, column 0
    np.testing.assert_array_equal(q, [64])  # one row up
    assert deck(ranges, elevation, None, 0.6)[0].size == 0  # deeper than the deck
    skip = np.zeros(ranges.shape, bool)
    skip[3, 0] = True  # nothing below p: no face under it
    assert deck(ranges, elevation, skip, 0.8)[0].size == 0
    level = _deck_column(0.7, above_x=14.0)  # above q a level surface, not a face
    assert deck(*level, None, 0.8)[0].size == 0
    # a run of 2 columns at 12 m of 64 spans 2 x 12 x 2 pi / 64 = 2.36 m; of 1 column 1.18 m
    two = _deck_column(0.7, columns=2)
    assert deck(*two, None, 0.8, deck_width_m=2.3)[0].size == 2
    assert deck(ranges, elevation, None, 0.8, deck_width_m=2.3)[0].size == 0


@pytest.mark.parametrize("ground", [None, "column"])
def test_bridge_deck_without_decks_gives_bridges_labels(small_sample, tmp_path, ground) -> None:
    # the script's method joins Bridge's clusters (found without the minimum size) over its deck
    # links and then drops the small ones: with no deck link it must be Bridge
    import numpy as np

    from flic_cli import registry
    from flic_cli.api import load_frame, segment_frame

    _bridge_deck()
    registry.register("method", "bridge-deck", registry.Entry("bridge_deck:BridgeDeck", "deck"))
    try:
        config = tmp_path / "deck.toml"
        config.write_text('[methods.deck0]\nkind = "bridge-deck"\ndeck_max_m = 0.0\n')
        for frame in range(3):
            data = load_frame(small_sample.kitti_root, frame)
            want = segment_frame(data, "bridge", ground=ground, config=config)
            got = segment_frame(data, "deck0", ground=ground, config=config)
            assert (want > 0).sum() > 1000
            np.testing.assert_array_equal(got, want)
    finally:
        registry.unregister("method", "bridge-deck")


@pytest.mark.parametrize(("upper", "kept"), [((3, 7), True), ((0, 21), False)])
def test_deck_within_keeps_an_upper_face_inside_the_lower_ones_columns(upper, kept) -> None:
    # a low face over columns 0-9 (rows 2, 3; cluster 1) and a face 0.7 m behind it (rows 0, 1;
    # cluster 2) over ``upper``'s columns: a cabin within the hood's outline is linked, a wall
    # reaching beyond it is not
    from types import SimpleNamespace

    import numpy as np

    module = _bridge_deck()
    ranges, elevation = _deck_column(0.7, columns=64)
    ranges[2:, 10:] = 0.0
    ranges[:2, : upper[0]] = 0.0
    ranges[:2, upper[1] :] = 0.0
    labels = np.zeros(ranges.shape, np.int64)
    labels[2:][ranges[2:] > 0] = 1
    labels[:2][ranges[:2] > 0] = 2
    image = SimpleNamespace(ranges=ranges, elevation=elevation)
    deck = module.BridgeDeck(deck_max_m=0.8, deck_within=True)
    p, q = deck.links(image, None, labels.reshape(-1))
    both = np.arange(max(upper[0], 0), min(upper[1], 10))
    np.testing.assert_array_equal(p, 2 * 64 + both if kept else [])
    p_any, _ = module.BridgeDeck(deck_max_m=0.8).links(image, None, labels.reshape(-1))
    np.testing.assert_array_equal(p_any, 2 * 64 + both)


@settings(max_examples=150, deadline=None)
@given(
    image=st.lists(st.sampled_from([0.0, 2.0, 2.3, 2.6, 3.4]), min_size=6 * 5, max_size=6 * 5),
    noise=st.lists(st.floats(-0.05, 0.05), min_size=6 * 5, max_size=6 * 5),
    deck_max=st.sampled_from([0.3, 0.8, 2.0]),
    upright=st.sampled_from([0.2, 0.5, 2.0]),
)
def test_deck_links_equal_their_definition_pixel_by_pixel(image, noise, deck_max, upright) -> None:
    # the vectorised links against the module docstring's test written out for every pixel, on
    # small random images of upright faces and steps (6 rows of 5 columns; each pixel's
    # horizontal range one of a few values, 0 = no node, with noise)
    import numpy as np

    elevation = np.radians([1.0, -2.0, -6.0, -10.0, -14.0, -18.0])
    horizontal = np.array(image).reshape(6, 5)
    ranges = np.where(horizontal > 0, horizontal + np.array(noise).reshape(6, 5), 0.0)
    ranges /= np.cos(elevation)[:, None]
    p, q = _bridge_deck().deck_links(ranges, elevation, None, deck_max, upright)
    x, z = ranges * np.cos(elevation)[:, None], ranges * np.sin(elevation)[:, None]
    want = []
    for r in range(2, 5):
        for c in range(5):
            b, a = (r + 1, c), (r - 2, c)
            if min(ranges[r + 1, c], ranges[r, c], ranges[r - 1, c], ranges[r - 2, c]) <= 0:
                continue
            if elevation[r] >= 0 or elevation[r - 1] >= 0:
                continue
            step = x[r - 1, c] - x[r, c]
            face_p = (z[r, c] - z[b]) * upright > abs(x[r, c] - x[b])
            face_q = (z[a] - z[r - 1, c]) * upright > abs(x[a] - x[r - 1, c])
            if face_p and face_q and 0 < step <= deck_max and z[r - 1, c] > z[r, c]:
                want.append(r * 5 + c)
    np.testing.assert_array_equal(np.sort(p), want)
    np.testing.assert_array_equal(q, p - 5)
