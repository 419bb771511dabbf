#!/usr/bin/env bash
# The sweeps of issue 23 that earlier runs could not finish (results/peers/sweeps/README.md):
# Euclidean (fast since the grid method) and the k = 32 ALPINEs on every shared frame and every
# sample frame, HDBSCAN (15-60 s per frame and value here) on a subset: the first frame of each
# shared sequence (5 frames, 24 objects) and the first two sample frames, four values.
# No-ground setting. Outputs in results/peers/sweeps/<method>/{kitti,sample0}/.
# Usage: scripts/peers_sweeps_rest.sh ../shared/data/semantickitti S0/semantickitti [JOBS]
# (S0: `flic sample S0 --frames 20 --seed 0`)
set -euo pipefail
kitti=$1
sample=$2
jobs=${3:-2}
out=results/peers/sweeps
run() {  # method, data name, data, extra args...
  local m=$1 name=$2 data=$3
  shift 3
  echo "flic sweep-threshold $data --method $m --setting no-ground --jobs $jobs $* --out $out/$m/$name"
  flic sweep-threshold "$data" --method "$m" --setting no-ground --jobs "$jobs" "$@" \
    --out "$out/$m/$name"
}
for name in kitti sample0; do
  data=$kitti
  [ "$name" = sample0 ] && data=$sample
  run euclidean "$name" "$data" --from 0.2 --to 1.2 --step 0.1
  # width_scale x width_m (0.45 m): 0.18 ... 0.9 m
  run alpine-agnostic "$name" "$data" --from 0.4 --to 2.0 --step 0.2
  # width_scale x each class's box width
  run alpine-k32 "$name" "$data" --from 0.6 --to 1.6 --step 0.2
done
run hdbscan kitti "$kitti" --frames 0:1 --from 10 --to 70 --step 20
run hdbscan sample0 "$sample" --frames 0:2 --from 10 --to 70 --step 20
