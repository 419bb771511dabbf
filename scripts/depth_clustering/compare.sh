#!/usr/bin/env bash
# Bogoslavskyi & Stachniss' C++ against flic in one session on one log, alternating:
# C++, flic, C++ (a disturbance by other work on the machine shows as a difference between the
# two C++ rounds). Writes OUT/cpp_round{1,2}.csv, OUT/flic/ (flic benchmark) and OUT/comparison.csv.
#
#   bash scripts/depth_clustering/compare.sh DC_CHECKOUT LOG OUT
set -euo pipefail
dc=$1 log=$2 out=$3
here=$(dirname "$0")
rm -rf "$out" && mkdir -p "$out"
bash "$here/time_cpp.sh" "$dc" "$log" 3 > "$out/cpp_round1.csv" 2> /dev/null
flic benchmark "$log" --methods bogoslavskyi,flic0,flic1,flic6,flic14 --rounds 3 --no-plots \
  --out "$out/flic"
bash "$here/time_cpp.sh" "$dc" "$log" 3 > "$out/cpp_round2.csv" 2> /dev/null
python - "$out" <<'PY'
import sys
from pathlib import Path

import pandas as pd

out = Path(sys.argv[1])
rows = []
for k in (1, 2):
    cpp = pd.read_csv(out / f"cpp_round{k}.csv")
    rows.append({"what": f"C++ ground + clustering, round {k}",
                 "median_ms": cpp.ground_and_clustering_us.median() / 1e3})
    rows.append({"what": f"C++ clustering alone, round {k}",
                 "median_ms": cpp.clustering_us.median() / 1e3})
ref = sum(r["median_ms"] for r in rows[0::2]) / 2  # C++ ground + clustering, both rounds
flic = pd.read_csv(out / "flic" / "summary.csv")
for r in flic[flic.kind == "method"].itertuples():
    rows.append({"what": f"flic {r.method} (own ground remover)", "median_ms": r.median_ms})
table = pd.DataFrame(rows)
table["times_faster_than_cpp_ground_and_clustering"] = ref / table.median_ms
table.to_csv(out / "comparison.csv", index=False)
print(table.round(3).to_string(index=False))
PY
