#!/usr/bin/env bash
# Rerun every result committed under results/ (results/README.md explains each one), from the
# repository root with ../shared beside it and the dev install active:
#     . .venv/bin/activate && bash scripts/make_results.sh [step ...]
# Steps: bench repeats evaluate ground sweeps coverage dbscan pictures (default: all, in this order;
# the benchmarks first, on a quiet machine, since evaluate takes its times from them), and cpp
# (not in the default: their C++ against flic; needs DC=<a PRBonn/depth_clustering checkout>
# and the system packages that scripts/depth_clustering/time_cpp.sh names).
# On a 2-core machine the whole run takes about half an hour. JOBS sets evaluate's processes.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=../shared/data/semantickitti
JOBS=${JOBS:-2}
LOG=${LOG:-/tmp/flic-bench-log}
# the 50 shared scans binned to 870 x 64: a Moosmann log with real ground (the synthetic one hides
# the road under its ego car; every remover finds there a fraction of the ground of a real log)
KLOG=${KLOG:-/tmp/flic-kitti-log}
METHODS=bogoslavskyi,flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan
PEERS=flic0-scipy,flic14-scipy
STEPS=${*:-bench repeats evaluate ground sweeps coverage dbscan pictures}

fresh() { rm -rf "$1"; }  # an output folder is rewritten whole (no stale files)

for step in $STEPS; do
  case $step in
  bench)
    # runtimes (paper Fig. 9, 10): a 500-frame synthetic 870 x 64 log and the 50 real frames,
    # each method with its own ground remover (and, on the log, with the paper's), one thread,
    # the paper-style scipy FLIC as a peer; each frame's median over several rounds (5: with 3,
    # p99/median of one method moved between 1.1 and 1.4 from run to run on this shared VM)
    test -d "$LOG/moosmann" || flic sample "$LOG" --frames 500
    fresh results/benchmark/synthetic-moosmann
    flic benchmark "$LOG/moosmann" --methods "$METHODS,$PEERS" --rounds 5 \
      --out results/benchmark/synthetic-moosmann
    fresh results/benchmark/synthetic-moosmann-paper-ground
    flic benchmark "$LOG/moosmann" --methods "$METHODS,$PEERS" --ground-remover paper \
      --rounds 5 --no-plots --out results/benchmark/synthetic-moosmann-paper-ground
    test -d "$KLOG" || python scripts/kitti_as_moosmann.py "$DATA" "$KLOG"
    fresh results/benchmark/kitti-as-moosmann
    flic benchmark "$KLOG" --methods "$METHODS,$PEERS" --rounds 5 --dbscan-every 2 \
      --out results/benchmark/kitti-as-moosmann
    fresh results/benchmark/kitti-as-moosmann-paper-ground
    flic benchmark "$KLOG" --methods "$METHODS,$PEERS" --ground-remover paper --rounds 5 \
      --dbscan-every 2 --no-plots --out results/benchmark/kitti-as-moosmann-paper-ground
    fresh results/benchmark/semantickitti
    flic benchmark "$DATA" --methods "$METHODS,$PEERS" --rounds 5 --dbscan-every 2 \
      --out results/benchmark/semantickitti
    python scripts/log_stats.py "$LOG/moosmann" > results/benchmark/synthetic-moosmann/log_stats.txt
    python scripts/log_stats.py "$KLOG" > results/benchmark/kitti-as-moosmann/log_stats.txt
    ;;
  repeats)
    # how much the benchmark figures move between runs of the same code: the log benchmarks
    # again with --rounds 3 (summaries only)
    test -d "$LOG/moosmann" || flic sample "$LOG" --frames 500
    test -d "$KLOG" || python scripts/kitti_as_moosmann.py "$DATA" "$KLOG"
    fresh results/benchmark/repeats
    for spec in "own-remover-rounds3:$LOG/moosmann:own" "paper-remover-rounds3-a:$LOG/moosmann:paper" \
      "paper-remover-rounds3-b:$LOG/moosmann:paper" "kitti-as-moosmann-own-remover-rounds3:$KLOG:own"; do
      IFS=: read -r name log remover <<< "$spec"
      tmp=$(mktemp -d)
      flic benchmark "$log" --methods "$METHODS" --ground-remover "$remover" --rounds 3 \
        --no-plots --out "$tmp"
      mkdir -p "results/benchmark/repeats/$name"
      cp "$tmp/summary.csv" "$tmp/environment.json" "results/benchmark/repeats/$name/"
      rm -rf "$tmp"
    done
    ;;
  evaluate)
    # Table 1 (both settings, the paper's ground extraction), panoptic quality with oracle
    # semantics, intervals, quality against speed (times of the benchmark above)
    fresh results/evaluate
    flic evaluate "$DATA" --setting both --semantics oracle --jobs "$JOBS" \
      --runtimes results/benchmark/semantickitti --out results/evaluate 2> "$LOG.err"
    # the estimate of the run's duration it printed before the bulk started
    tr '\r' '\n' < "$LOG.err" | grep '^estimate' > results/evaluate/estimate.txt
    rm -rf results/evaluate/parts
    # which differences between methods are significant (paired bootstrap over frames)
    python scripts/paired_differences.py results/evaluate
    ;;
  ground)
    # the ground setting with every other remover (the paper's is in results/evaluate)
    for remover in column bogoslavskyi patchworkpp; do
      fresh "results/ground/evaluate-$remover"
      flic evaluate "$DATA" --setting ground --ground-remover "$remover" --jobs "$JOBS" \
        --runtimes results/benchmark/semantickitti --out "results/ground/evaluate-$remover"
      rm -rf "results/ground/evaluate-$remover/parts"
    done
    python scripts/ground_figure.py "$DATA" --sequence 08 --frame 0 \
      --out results/ground/ground_masks_08_000000.png
    ;;
  sweeps)
    # threshold studies (paper Fig. 8), no-ground setting (Bridge's grid of variants behind its
    # defaults is in results/sweep/bridge/, with its own commands)
    for spec in "flic0:--method flic --mc 0" "flic1-map:--method flic --mc 1" \
      "flic1-neighbour:--method flic1n" "bogoslavskyi:--method bogoslavskyi" \
      "dbscan:--method dbscan" "bridge-default:--method bridge"; do
      name=${spec%%:*}
      fresh "results/sweep/$name"
      # shellcheck disable=SC2086
      flic sweep-threshold "$DATA" ${spec#*:} --jobs "$JOBS" --out "results/sweep/$name"
    done
    ;;
  coverage)
    python scripts/projection_coverage.py
    ;;
  dbscan)
    python scripts/dbscan_backends.py "$DATA" results/dbscan-backends
    ;;
  pictures)
    # a segmented scan: range image and bird's-eye / 3D views, ground truth beside prediction
    tmp=$(mktemp -d)
    for method in bridge flic14; do
      flic segment "$DATA" --sequences 08 --frames 0:1 --method "$method" --render 0 \
        --out "$tmp/$method"
      cp "$tmp/$method/render_08_000000.png" "results/segment/${method}_08_000000_range.png"
      cp "$tmp/$method/views_08_000000.png" "results/segment/${method}_08_000000_views.png"
    done
    rm -rf "$tmp"
    ;;
  cpp)
    # Bogoslavskyi & Stachniss' own C++ and flic, alternating in one session, on both logs above
    # (their reader subtracts its per-row range corrections of the Karlsruhe sensor from every
    # log: a few centimetres per row, at most 0.2 m, which can move what their remover takes as
    # ground, and with it their time, a little)
    test -d "$LOG/moosmann" || flic sample "$LOG" --frames 500
    bash scripts/depth_clustering/compare.sh "${DC:?set DC to a depth_clustering checkout}" \
      "$LOG/moosmann" results/benchmark/cpp-comparison
    test -d "$KLOG" || python scripts/kitti_as_moosmann.py "$DATA" "$KLOG"
    bash scripts/depth_clustering/compare.sh "$DC" "$KLOG" \
      results/benchmark/cpp-comparison-kitti-as-moosmann
    ;;
  *)
    echo "unknown step $step" >&2
    exit 2
    ;;
  esac
done
