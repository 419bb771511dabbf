#!/usr/bin/env bash
# "Which clusterer?" (issue 23) in one command: every method, old and new, on the shared
# SemanticKITTI frames, in both settings, with oracle semantics (PQ), OSE / USE and intervals,
# plus `flic benchmark`'s median ms per frame; then the table and picture.
#   1. flic evaluate, no-ground setting, the default methods with semantics (default_methods +
#      default_semantic_methods: everything but hdbscan), all frames;
#   2. the same in the ground setting with flic's column remover;
#   3. hdbscan (about 80 s per frame) on the first frame of each sequence, both settings;
#   4. flic benchmark of every method (ground setting, column remover), the slow ones (dbscan,
#      hdbscan) on every 25th frame;
#   5. scripts/peers_which_clusterer.py: results/peers/which_clusterer/which_clusterer.{csv,png}.
# 31 min of wall time on 2 cores shared with other work (load 11-15), 02 Dec.
# Usage: scripts/peers_which_clusterer.sh [DATA] [OUT] [JOBS]
#   (defaults: ../shared/data/semantickitti, results/peers, 2)
set -euo pipefail
data=${1:-../shared/data/semantickitti}
out=${2:-results/peers}
jobs=${3:-2}
ev=$out/evaluate
say() { echo "+ $*"; "$@"; }
rm -rf "$ev/no-ground" "$ev/ground" "$ev/hdbscan-no-ground" "$ev/hdbscan-ground" "$out/benchmark"
say flic evaluate "$data" --setting no-ground --semantics oracle --jobs "$jobs" \
  --out "$ev/no-ground"
say flic evaluate "$data" --setting ground --ground-remover column --semantics oracle \
  --jobs "$jobs" --out "$ev/ground"
say flic evaluate "$data" --frames 0:1 --setting no-ground --semantics oracle --jobs "$jobs" \
  --methods hdbscan --out "$ev/hdbscan-no-ground"
say flic evaluate "$data" --frames 0:1 --setting ground --ground-remover column \
  --semantics oracle --jobs "$jobs" --methods hdbscan --out "$ev/hdbscan-ground"
methods=$(python -c "from flic_cli.config import load_config as l; c = l(None); \
print(','.join([*c.default_methods, *c.default_semantic_methods, 'hdbscan']))")
say flic benchmark "$data" --methods "$methods" --setting ground --ground-remover column \
  --warmup 1 --slow-every 25 --out "$out/benchmark"
rm -rf "$ev"/*/parts
say python scripts/peers_which_clusterer.py "$out/which_clusterer" --benchmark "$out/benchmark" \
  --no-ground "$ev/no-ground" "$ev/hdbscan-no-ground" --ground "$ev/ground" "$ev/hdbscan-ground"
