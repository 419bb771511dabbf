#!/usr/bin/env bash
# SUPERSEDED by scripts/peers_sweeps_rest.sh (every frame); kept until make_results.sh calls that.
# The sweeps that scripts/peers_sweeps.sh and peers_sweeps_k32.sh could not finish on the shared
# machine this session (Euclidean ran at minutes per frame there, ALPINE k = 32 at 90 s per frame
# over 13 values), cut down: 5 shared frames (the first of each sequence) and 5 sample frames,
# fewer values. HDBSCAN's sweep was not run (tens of seconds per frame and value).
# Usage: scripts/peers_sweeps_small.sh ../shared/data/semantickitti S0/semantickitti
set -euo pipefail
out=results/peers/sweeps
run() {
  echo "flic sweep-threshold $*"
  flic sweep-threshold "$@"
}
run "$1" --method euclidean --setting no-ground --frames 0:1 --from 0.2 --to 1.2 --step 0.2 \
  --out $out/euclidean/kitti
run "$2" --method euclidean --setting no-ground --frames 0:5 --from 0.2 --to 1.2 --step 0.2 \
  --out $out/euclidean/sample0
run "$1" --method alpine-agnostic --setting no-ground --frames 0:1 --from 0.5 --to 1.3 --step 0.2 \
  --out $out/alpine-agnostic/kitti
run "$2" --method alpine-agnostic --setting no-ground --frames 0:5 --from 0.5 --to 1.3 --step 0.2 \
  --out $out/alpine-agnostic/sample0
