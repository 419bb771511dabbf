#!/usr/bin/env bash
# SUPERSEDED by scripts/peers_sweeps_rest.sh (every frame); kept until make_results.sh calls that.
# ALPINE with k = 32 (presets alpine-k32 and alpine-agnostic), swept like scripts/peers_sweeps.sh
# (whose alpine-agnostic runs used k = 8 and are kept in results/peers/sweeps/alpine-agnostic-k8/).
# Usage: scripts/peers_sweeps_k32.sh ../shared/data/semantickitti S0/semantickitti
set -euo pipefail
out=results/peers/sweeps
for m in alpine-agnostic alpine-k32; do
  for name in kitti sample0; do
    data=$1
    [ "$name" = sample0 ] && data=$2
    echo "flic sweep-threshold $data --method $m --setting no-ground --from 0.4 --to 1.6 --step 0.1 --out $out/$m/$name"
    flic sweep-threshold "$data" --method "$m" --setting no-ground --from 0.4 --to 1.6 --step 0.1 \
      --out "$out/$m/$name"
  done
done
