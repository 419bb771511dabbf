#!/usr/bin/env bash
# The main parameter of each of issue 23's methods swept (no-ground setting) on the 50 shared
# SemanticKITTI frames and on the synthetic sample (flic sample S0 --frames 20), outputs in
# results/peers/sweeps/<method>/{kitti,sample0}/. Frame counts are cut where a method is slow
# (the machine is shared). Euclidean, the k = 32 ALPINEs and HDBSCAN are swept by
# scripts/peers_sweeps_rest.sh (alpine-agnostic-k8/ came from this script when the preset had
# k = 8 and cannot be remade from the presets now).
# Usage: scripts/peers_sweeps.sh ../shared/data/semantickitti S0/semantickitti
set -euo pipefail
kitti=$1
sample=$2
out=results/peers/sweeps
run() {  # method, data name, data, extra args...
  local m=$1 name=$2 data=$3
  shift 3
  echo "flic sweep-threshold $data --method $m --setting no-ground $* --out $out/$m/$name"
  flic sweep-threshold "$data" --method "$m" --setting no-ground "$@" --out "$out/$m/$name"
}
for name in kitti sample0; do
  data=$kitti
  [ "$name" = sample0 ] && data=$sample
  run slr "$name" "$data" --from 0.1 --to 1.5 --step 0.1
  run cvc "$name" "$data" --from 0.1 --to 1.5 --step 0.1
  run alpine "$name" "$data" --from 0.4 --to 1.6 --step 0.1
done
