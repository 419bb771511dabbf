#!/usr/bin/env bash
# The main parameter of each of issue 23's methods swept (no-ground setting) on the 50 shared
# SemanticKITTI frames and on the synthetic sample (S0: `flic sample S0 --frames 20 --seed 0`),
# outputs in results/peers/sweeps/<method>/{kitti,sample0}/ (README.md there). Every method on
# every frame but HDBSCAN (15-60 s per frame and value on a 2-core machine): the first frame of
# each shared sequence (5 frames, 24 objects) and the first two sample frames, four values.
# Usage: scripts/peers_sweeps.sh ../shared/data/semantickitti S0/semantickitti [JOBS]
set -euo pipefail
kitti=$1
sample=$2
jobs=${3:-2}
out=results/peers/sweeps
run() {  # method, data name, data, extra args...
  local m=$1 name=$2 data=$3
  shift 3
  echo "flic sweep-threshold $data --method $m --setting no-ground --jobs $jobs $* --out $out/$m/$name"
  rm -rf "$out/$m/$name"
  flic sweep-threshold "$data" --method "$m" --setting no-ground --jobs "$jobs" "$@" \
    --out "$out/$m/$name"
}
for name in kitti sample0; do
  data=$kitti
  [ "$name" = sample0 ] && data=$sample
  run slr "$name" "$data" --from 0.1 --to 1.5 --step 0.1
  run cvc "$name" "$data" --from 0.1 --to 1.5 --step 0.1
  run alpine "$name" "$data" --from 0.4 --to 1.6 --step 0.1
  run euclidean "$name" "$data" --from 0.2 --to 1.2 --step 0.1
  # width_scale x width_m (0.45 m): 0.18 ... 0.9 m
  run alpine-agnostic "$name" "$data" --from 0.4 --to 2.0 --step 0.2
  # width_scale x each class's box width
  run alpine-k32 "$name" "$data" --from 0.6 --to 1.6 --step 0.2
done
run hdbscan kitti "$kitti" --frames 0:1 --from 10 --to 70 --step 20
run hdbscan sample0 "$sample" --frames 0:2 --from 10 --to 70 --step 20
