"""Memory flat in a bag's length: `flic segment BAG --export mcap` on 20 and on 300 real
revolutions, each in a subprocess whose peak RSS is read (scripts/bags/bag_memory.py does 2,000)."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("rosbags")

import bagtools  # noqa: E402

CHILD = (
    "import resource, subprocess, sys; "
    "r = subprocess.run(sys.argv[1:], capture_output=True, text=True); "
    "sys.stderr.write(r.stderr[-3000:]); "
    "print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)


def _peak_kb(bag, out) -> int:
    flic = [sys.executable, "-c", "from flic_cli.cli import main; main()"]
    args = [*flic, "segment", str(bag), "--method", "flic14", "--export", "mcap", "--out", str(out)]
    done = subprocess.run(
        [sys.executable, "-c", CHILD, *args], capture_output=True, text=True, check=True
    )
    code, kb = done.stdout.split()
    assert code == "0", done.stderr
    return int(kb)


@pytest.mark.slow
def test_peak_memory_does_not_grow_with_the_bag(shared_data, tmp_path):
    short = bagtools.cycled_vlp16_bag(shared_data, tmp_path / "short", 20)
    long = bagtools.cycled_vlp16_bag(shared_data, tmp_path / "long", 300)
    peak_short = _peak_kb(short, tmp_path / "out_short")
    peak_long = _peak_kb(long, tmp_path / "out_long")
    exported = list((tmp_path / "out_long").glob("*_flic_mcap/*.mcap"))
    assert len(exported) == 1 and exported[0].stat().st_size > 80e6  # 300 revolutions written
    # one revolution held at a time: 15 times the frames may not cost more than a few MB (a
    # frame held per revolution would add ~1.5 MB each, 420 MB over 280 frames)
    assert peak_long <= peak_short * 1.05 + 10_000, (peak_short, peak_long)
