#!/usr/bin/env bash
# Remake every result committed under results/ with the commands that results/README.md and
# results/ground/README.md write next to each file. From the repository root, with ../shared
# beside it and the dev install active:
#     . .venv/bin/activate && bash scripts/make_results.sh [step ...]
#     bash scripts/make_results.sh --list      # the steps: what each remakes, what it needs
# Steps, in this order (default: all of them):
#     bench repeats revisions evaluate ground synthetic ground-sweep ground-speed sweeps
#     bridge-grid bridge-cases coverage labels dbscan pictures profile sensors sensors-synthetic bags peers cpp
#     panoptic ouster-sdk peers-fidelity
# The benchmarks come first, on a quiet machine: evaluate and ground take their times from them.
# Every step's start, end and wall time go to $TMP_RESULTS/steps.log (default
# /tmp/flic-results/steps.log), one tab-separated line per step: step, start (UTC), seconds,
# status (done, skipped, failed), so that a later run can be planned from an earlier one.
# Four steps need something outside the repository; without it they say so and are skipped:
#     cpp       Bogoslavskyi & Stachniss' own C++: DC=<a PRBonn/depth_clustering checkout>, and
#               the system packages that scripts/depth_clustering/time_cpp.sh names;
#               also remakes results/ground/bogoslavskyi_fidelity*.csv (their ground masks)
#     panoptic  semantic-kitti-api's own scores: SKAPI=<a PRBonn/semantic-kitti-api checkout>,
#               in a Python with numpy and pyyaml
#     ouster-sdk  flic's Ouster decoding against ouster-sdk's: OUSTER_PY=<a Python with
#               ouster-sdk installed, outside the project's environment>
#     peers-fidelity  the field's clusterers against their reference code: FLIC_REF=<the folder
#               where scripts/peers_fidelity.sh built valeoai/Alpine, CVC, SLR and PCL's Euclidean>
# revisions makes a git worktree and a venv per revision under $TMP_RESULTS/revisions (pip
# installs the revision's dependencies, which must be reachable; BEFORE and AFTER name them).
# ground-sweep and bridge-grid are the longest steps (many evaluations of the 50 frames each).
# JOBS sets the processes of evaluate and sweep-threshold.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=../shared/data/semantickitti
JOBS=${JOBS:-2}
TMP=${TMP_RESULTS:-/tmp/flic-results}
LOG=$TMP/bench-log            # the synthetic 870 x 64 Moosmann log (500 frames)
KLOG=$TMP/kitti-log           # the 50 shared scans binned to 870 x 64: a log with real ground
METHODS=bogoslavskyi,flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan
PEERS=flic0-scipy,flic14-scipy
GROUND_METHODS=flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,dbscan-fast
DEFAULT="bench repeats revisions evaluate ground synthetic ground-sweep ground-speed sweeps bridge-grid"
DEFAULT="$DEFAULT bridge-cases coverage labels dbscan pictures profile sensors sensors-synthetic bags peers cpp"
DEFAULT="$DEFAULT panoptic ouster-sdk peers-fidelity"
SENSORS=../shared/data/sensors
# step, what it remakes, what it needs besides ../shared and the dev install (the wall time of
# each step is measured into steps.log, not guessed here)
list_steps() {
  cat <<'LIST'
bench             results/benchmark/{synthetic-moosmann,kitti-as-moosmann,semantickitti}*    quiet machine
repeats           results/benchmark/repeats/                                               quiet machine
revisions         results/benchmark/revisions/ (BEFORE=3e00d28 against AFTER=HEAD)         network or pip cache, quiet machine
evaluate          results/evaluate/                                                        -
ground            results/ground/{evaluate-*,table,gap_intervals_column,oracle*,losses_*,pixel_heights,ground_masks*}  -
synthetic         results/ground/evaluate-column-synthetic-seed7/, gap_intervals_column_synthetic_seed7.csv  -
ground-sweep      results/ground/sweep_column*.csv                                         -
ground-speed      results/ground/speed_per_point_*.csv                                     quiet machine
sweeps            results/sweep/{flic0,flic1-map,flic1-neighbour,bogoslavskyi,dbscan,bridge-default}/  -
bridge-grid       results/sweep/bridge/{kitti,sample0,sample1}/                            -
bridge-cases      results/bridge-cases/ (speed/: quiet machine)                            -
coverage          results/projection_coverage.csv                                          -
labels            results/labels/fingerprint.csv                                           -
dbscan            results/dbscan-backends/                                                 -
pictures          results/segment/                                                         -
profile           results/profile/                                                         quiet machine
sensors           results/sensors/ (but ouster_sdk_comparison.csv)                         ../shared/data/sensors
sensors-synthetic results/sensors-synthetic/                                               -
bags              results/bags/                                                            -
peers             results/peers/{evaluate,benchmark,which_clusterer,sweeps,alpine-k}/      -
cpp               results/benchmark/cpp-comparison*/, results/ground/bogoslavskyi_fidelity*.csv  DC=depth_clustering
panoptic          results/panoptic/ (but README.md)                                        SKAPI=semantic-kitti-api
ouster-sdk        results/sensors/ouster_sdk_comparison.csv                                OUSTER_PY=python with ouster-sdk
peers-fidelity    results/peers/fidelity/                                                  FLIC_REF=built references
LIST
}
if [ "${1:-}" = "--list" ]; then
  list_steps
  exit 0
fi
STEPS=${*:-$DEFAULT}
mkdir -p "$TMP"
STEPLOG=$TMP/steps.log

# step_log STATUS: one line per step into $STEPLOG (step, start UTC, seconds, status)
step_log() {
  printf '%s\t%s\t%s\t%s\n' "$step" "$(date -u -d "@$t0" +%FT%TZ)" "$(($(date +%s) - t0))" "$1" \
    >> "$STEPLOG"
}
skip() {  # skip REASON: a step whose outside requirement is missing
  echo "step $step skipped: $1" >&2
  step_log skipped
}
trap 'step_log "failed (exit $?)"' ERR

fresh() { rm -rf "$1"; }  # an output folder is rewritten whole (no stale files)
keep() {  # keep DIR FILE...: remove every other file a command wrote into DIR (nothing cites it)
  local dir=$1 f name
  shift
  for f in "$dir"/*; do
    name=${f##*/}
    [[ " $* " == *" $name "* ]] || rm -rf "$f"
  done
}
synthetic_log() { test -d "$LOG/moosmann" || flic sample "$LOG" --frames 500; }
kitti_log() { test -d "$KLOG" || python scripts/kitti_as_moosmann.py "$DATA" "$KLOG"; }
sample() {  # sample FOLDER FRAMES SEED
  test -d "$1/semantickitti" || flic sample "$1" --frames "$2" --seed "$3"
}

for step in $STEPS; do
  echo "== make_results: $step" >&2
  t0=$(date +%s)
  case $step in
  bench)
    # runtimes (paper Fig. 9, 10): results/README.md section 3
    synthetic_log
    kitti_log
    fresh results/benchmark/synthetic-moosmann
    flic benchmark "$LOG/moosmann" --methods "$METHODS,$PEERS" --rounds 5 \
      --out results/benchmark/synthetic-moosmann
    fresh results/benchmark/synthetic-moosmann-paper-ground
    flic benchmark "$LOG/moosmann" --methods "$METHODS,$PEERS" --ground-remover paper \
      --rounds 5 --no-plots --out results/benchmark/synthetic-moosmann-paper-ground
    fresh results/benchmark/kitti-as-moosmann
    flic benchmark "$KLOG" --methods "$METHODS,$PEERS" --rounds 5 --slow-every 2 \
      --out results/benchmark/kitti-as-moosmann
    fresh results/benchmark/kitti-as-moosmann-paper-ground
    flic benchmark "$KLOG" --methods "$METHODS,$PEERS" --ground-remover paper --rounds 5 \
      --slow-every 2 --no-plots --out results/benchmark/kitti-as-moosmann-paper-ground
    fresh results/benchmark/semantickitti
    flic benchmark "$DATA" --methods "$METHODS,$PEERS" --rounds 5 --slow-every 2 \
      --out results/benchmark/semantickitti
    python scripts/log_stats.py "$LOG/moosmann" > results/benchmark/synthetic-moosmann/log_stats.txt
    python scripts/log_stats.py "$KLOG" > results/benchmark/kitti-as-moosmann/log_stats.txt
    ;;
  repeats)
    # how much the benchmark figures move between runs of the same code (summaries only)
    synthetic_log
    kitti_log
    fresh results/benchmark/repeats
    for spec in "synthetic-own:$LOG/moosmann:own" "synthetic-paper-a:$LOG/moosmann:paper" \
      "synthetic-paper-b:$LOG/moosmann:paper" "kitti-as-moosmann-own:$KLOG:own"; do
      IFS=: read -r name log remover <<< "$spec"
      tmp=$(mktemp -d)
      flic benchmark "$log" --methods "$METHODS" --ground-remover "$remover" --rounds 3 \
        --no-plots --out "$tmp"
      mkdir -p "results/benchmark/repeats/$name"
      cp "$tmp/summary.csv" "$tmp/environment.json" "results/benchmark/repeats/$name/"
      rm -rf "$tmp"
    done
    ;;
  revisions)
    # flic benchmark of two revisions, alternating round by round on one core, on the synthetic
    # 200-frame log and the 50 shared frames: results/benchmark/revisions/README.md
    L200=$TMP/log-200
    test -d "$L200/moosmann" || flic sample "$L200" --frames 200
    for set in "synthetic-moosmann:$L200/moosmann" "semantickitti:$DATA"; do
      name=${set%%:*} data=${set#*:}
      fresh "results/benchmark/revisions/$name"
      python scripts/benchmark_revisions.py "${BEFORE:-3e00d28}" "${AFTER:-HEAD}" --data "$data" \
        --rounds 6 --cpu "${CPU:-1}" --work "$TMP/revisions" --out "results/benchmark/revisions/$name"
    done
    # clustering alone (the no-ground setting times no remover)
    fresh results/benchmark/revisions/semantickitti-no-ground
    python scripts/benchmark_revisions.py "${BEFORE:-3e00d28}" "${AFTER:-HEAD}" --data "$DATA" \
      --methods bogoslavskyi,flic0,flic6,flic14,flic6n,bridge --extra "--setting no-ground" \
      --rounds 4 --cpu "${CPU:-1}" --work "$TMP/revisions" \
      --out results/benchmark/revisions/semantickitti-no-ground
    # the A/A control: the later revision against itself, how far the machine alone moves a ratio
    fresh results/benchmark/revisions/synthetic-moosmann-aa
    python scripts/benchmark_revisions.py "${AFTER:-HEAD}" "${AFTER:-HEAD}" --data "$L200/moosmann" \
      --rounds 4 --cpu "${CPU:-1}" --work "$TMP/revisions" \
      --out results/benchmark/revisions/synthetic-moosmann-aa
    # the methods alone, interleaved in one run (finer than flic benchmark): kernels.txt
    base=$TMP/revisions/$(git rev-parse "${BEFORE:-3e00d28}" | cut -c1-12)  # benchmark_revisions.py's worktree
    maps=$(python -c 'print([[k, k] for k in range(2, 16)])')
    {
      for spec in "flic_cli.methods.bogoslavskyi:Bogoslavskyi:{}" "flic_cli.methods.flic:Flic:{}" \
        "flic_cli.methods.flic:Flic:{\"maps\": $maps}" "flic_cli.methods.bridge:Bridge:{}"; do
        IFS=: read -r module cls params <<< "$spec"
        echo "# python scripts/kernel_revisions.py --data $DATA --method $module:$cls --params '$params' --rounds 20 --repeat 3 --cpu ${CPU:-1} before=$base after=. after2=."
        python scripts/kernel_revisions.py --data "$DATA" --method "$module:$cls" \
          --params "$params" --rounds 20 --repeat 3 --cpu "${CPU:-1}" \
          before="$base" after=. after2=.
      done
    } > "$TMP/kernels.txt"
    mv "$TMP/kernels.txt" results/benchmark/revisions/kernels.txt
    ;;
  evaluate)
    # Table 1 (both settings, the paper's ground extraction), panoptic quality with oracle
    # semantics, intervals, quality against speed: results/README.md sections 1, 5, 7
    fresh results/evaluate
    flic evaluate "$DATA" --setting both --semantics oracle --jobs "$JOBS" \
      --runtimes results/benchmark/semantickitti --out results/evaluate 2> "$TMP/evaluate.err"
    # the estimate of the run's duration it printed before the bulk started
    tr '\r' '\n' < "$TMP/evaluate.err" | grep '^estimate' > results/evaluate/estimate.txt
    rm -rf results/evaluate/parts
    python scripts/paired_differences.py results/evaluate
    ;;
  ground)
    # every other remover in both settings, the ground table, the gaps' intervals, the labels
    # as masks, where the gap goes, the pixels' heights, the figure: results/ground/README.md
    for remover in column bogoslavskyi patchworkpp; do
      fresh "results/ground/evaluate-$remover"
      flic evaluate "$DATA" --setting both --ground-remover "$remover" --jobs "$JOBS" \
        --runtimes results/benchmark/semantickitti --out "results/ground/evaluate-$remover"
      rm -rf "results/ground/evaluate-$remover/parts"
    done
    python scripts/ground_study.py table "$DATA" --evaluate paper=results/evaluate \
      --evaluate bogoslavskyi=results/ground/evaluate-bogoslavskyi \
      --evaluate column=results/ground/evaluate-column \
      --evaluate patchworkpp=results/ground/evaluate-patchworkpp --out results/ground/table.csv
    python scripts/paired_differences.py results/ground/evaluate-column --settings \
      --out results/ground/gap_intervals_column.csv
    python scripts/ground_study.py oracle "$DATA" --methods "$GROUND_METHODS" \
      --out results/ground/oracle.csv --counts
    for m in flic0 flic14 bridge dbscan; do
      python scripts/ground_study.py losses "$DATA" --method "$m" --remover column \
        --out "results/ground/losses_$m"
    done
    python scripts/ground_study.py heights "$DATA" --out results/ground/pixel_heights.csv
    python scripts/ground_study.py figure "$DATA" --sequence 08 --frame 0 \
      --out results/ground/ground_masks_08_000000.png
    ;;
  synthetic)
    # column on a synthetic sample none of its parameters was chosen on (people, cyclists)
    S7=$TMP/sample-seed7
    sample "$S7" 60 7
    out=results/ground/evaluate-column-synthetic-seed7
    fresh "$out"
    flic evaluate "$S7/semantickitti" --setting both --ground-remover column --jobs "$JOBS" \
      --out "$out"
    python scripts/paired_differences.py "$out" --settings \
      --out results/ground/gap_intervals_column_synthetic_seed7.csv
    # summaries only (the per-object and per-frame tables of 60 synthetic frames are large)
    keep "$out" by_class.csv ground.csv per_setting.csv table.csv
    ;;
  ground-sweep)
    # column's parameters, one at a time around the defaults (shared frames + 20 synthetic)
    python scripts/ground_study.py sweep "$DATA" --params \
      neighbour_px,neighbour_band_m,foot_deg,under_m,face_deg,base_band_m,point_heights,hidden_points \
      --methods "$GROUND_METHODS" --out results/ground/sweep_column_neighbours.csv
    python scripts/ground_study.py sweep "$DATA" --params hold_feet,attach_m \
      --methods "$GROUND_METHODS" --out results/ground/sweep_column_hold.csv
    python scripts/ground_study.py sweep "$DATA" --out results/ground/sweep_column.csv \
      --params noise_m,slope_change_deg,kerb_m,max_step_m,flat_deg,seed_tolerance_m,base_band_m \
      --methods flic0,flic6,flic14
    ;;
  ground-speed)
    # the removers alone, interleaved
    kitti_log
    python scripts/ground_study.py speed "$DATA" --removers column,paper,bogoslavskyi,patchworkpp \
      --rounds 3 --out results/ground/speed_per_point_semantickitti.csv
    python scripts/ground_study.py speed "$KLOG" --removers column,paper,bogoslavskyi,patchworkpp \
      --rounds 5 --out results/ground/speed_per_point_kitti-as-moosmann.csv
    python scripts/ground_study.py speed "$DATA" \
      --removers column,column:hidden_points=False,paper,patchworkpp --rounds 3 \
      --out results/ground/speed_per_point_without_step7_semantickitti.csv
    ;;
  sweeps)
    # threshold studies (paper Fig. 8), no-ground setting: results/README.md section 2
    for spec in "flic0:--method flic --mc 0" "flic1-map:--method flic --mc 1" \
      "flic1-neighbour:--method flic1n" "bogoslavskyi:--method bogoslavskyi" \
      "dbscan:--method dbscan" "bridge-default:--method bridge"; do
      name=${spec%%:*}
      fresh "results/sweep/$name"
      # shellcheck disable=SC2086
      flic sweep-threshold "$DATA" ${spec#*:} --jobs "$JOBS" --out "results/sweep/$name"
    done
    ;;
  bridge-grid)
    # Bridge's variants behind its defaults: results/sweep/bridge/README.md
    sample "$TMP/sample-seed0" 20 0
    sample "$TMP/sample-seed1" 20 1
    for set in "kitti:$DATA" "sample0:$TMP/sample-seed0/semantickitti" \
      "sample1:$TMP/sample-seed1/semantickitti"; do
      name=${set%%:*} data=${set#*:}
      for v in bridge_g0_r12 bridge_g150_r12 bridge_g175_r12 bridge_g200_r12 bridge_g225_r12 \
        bridge_g250_r12 bridge_g200_r4 bridge_g200_r8 bridge_g200_r16 bridge_g200_r24; do
        out=results/sweep/bridge/$name/$v
        fresh "$out"
        flic sweep-threshold "$data" --config configs/bridge-sweep.toml --method "$v" \
          --setting no-ground --from 0.2 --to 1.0 --step 0.05 --jobs "$JOBS" --out "$out"
        # the plot only for the chosen variant
        test "$v" = bridge_g200_r12 || rm -f "$out/sweep.png"
      done
    done
    ;;
  bridge-cases)
    # Bridge's weak cases and the rules measured against them: results/bridge-cases/README.md.
    # One evaluation per data set with every variant of configs/bridge-cases.toml.
    BC=$TMP/bridge-cases
    test -f "$BC/cases.csv" || python scripts/bridge_cases.py "$BC"
    # Bridge and every variant the config defines (read from it, not listed twice)
    VARIANTS=$(python -c 'import sys, tomllib
print(",".join(["bridge", *tomllib.load(open(sys.argv[1], "rb"))["methods"]]))' \
      configs/bridge-cases.toml)
    sample "$TMP/sample-seed0" 20 0
    sample "$TMP/sample-seed1" 20 1
    for set in "cases:$BC:$VARIANTS,flic0,bogoslavskyi:no-ground" \
      "kitti:$DATA:$VARIANTS:both" \
      "sample0:$TMP/sample-seed0/semantickitti:$VARIANTS,flic0,bogoslavskyi:both" \
      "sample1:$TMP/sample-seed1/semantickitti:$VARIANTS,flic0,bogoslavskyi:both"; do
      IFS=: read -r name data methods setting <<< "$set"
      out=results/bridge-cases/$name
      fresh "$out"
      flic evaluate "$data" --config configs/bridge-cases.toml --methods "$methods" \
        --setting "$setting" --ground-remover column --semantics oracle --jobs "$JOBS" --out "$out"
      python scripts/paired_differences.py "$out" --out "$out/paired.csv"
      # the mean IoU per case, spacing and range (reads per_object.csv)
      if [ "$name" = cases ]; then
        python scripts/bridge_cases.py "$BC" --table "$out" --dest results/bridge-cases
      fi
      keep "$out" table.csv by_class.csv by_distance.csv paired.csv
    done
    cp "$BC/cases.csv" results/bridge-cases/cases/objects.csv
    # the open-holes variants and the Bridge without the level rule on every sensor profile's
    # street (seed 0, 10 frames), as in step sensors-synthetic (whose other methods' figures they
    # sit beside)
    fresh results/bridge-cases/profiles
    python scripts/sensors_study.py profiles --frames 10 --out results/bridge-cases/profiles \
      --work "$TMP/bridge-cases-sensors" \
      --methods bridge,bridge-no-level,bridge-no-hole-limit,bridge-open3,bridge-open6 \
      --extra-config configs/bridge-cases.toml --jobs "$JOBS"
    for d in results/bridge-cases/profiles/*/; do keep "$d" table.csv by_class.csv differences.csv; done
    rm -f results/bridge-cases/profiles/geometry.csv
    # the deck link, measured and not built (scripts/bridge_deck.py, one process per data set:
    # its method kind is registered in that process), on the same data sets and streets
    deck=results/bridge-cases/deck
    fresh "$deck"
    for set in "cases:$BC:no-ground" "kitti:$DATA:both" \
      "sample0:$TMP/sample-seed0/semantickitti:both" "sample1:$TMP/sample-seed1/semantickitti:both"; do
      IFS=: read -r name data setting <<< "$set"
      python scripts/bridge_deck.py "$data" "$deck/$name" --setting "$setting"
      keep "$deck/$name" table.csv by_class.csv paired.csv links.csv
    done
    for d in "$TMP"/bridge-cases-sensors/*/; do
      s=$(basename "$d")
      python scripts/bridge_deck.py "$d/semantickitti" "$deck/profiles/$s" \
        --config "$TMP/bridge-cases-sensors/$s.config.toml"
      keep "$deck/profiles/$s" table.csv by_class.csv paired.csv links.csv
    done
    # Bridge with the removed ground's returns seen as free space (scripts/ground_study.py oracle's "labels,
    # per point" row against the no-ground setting), on the scenes and three samples
    sample "$TMP/sample-seed7" 60 7
    for set in "cases:$BC" "sample0:$TMP/sample-seed0/semantickitti" \
      "sample1:$TMP/sample-seed1/semantickitti" "sample7:$TMP/sample-seed7/semantickitti"; do
      name=${set%%:*} data=${set#*:}
      mkdir -p "results/bridge-cases/$name"
      python scripts/ground_study.py oracle "$data" --methods bridge,flic0 \
        --out "results/bridge-cases/$name/ground_seen.csv"
    done
    # speed: every variant with its ground extraction, interleaved (quiet machine)
    L100=$TMP/log-100
    test -d "$L100/moosmann" || flic sample "$L100" --frames 100
    fresh results/bridge-cases/speed
    flic benchmark "$L100/moosmann" --config configs/bridge-cases.toml --methods "$VARIANTS" \
      --rounds 5 --threads 1 --no-plots --out results/bridge-cases/speed
    keep results/bridge-cases/speed summary.csv environment.json
    ;;
  coverage)
    python scripts/projection_coverage.py "$DATA" --out results/projection_coverage.csv
    ;;
  labels)
    python scripts/check_labels.py --shared "$DATA" --out results/labels/fingerprint.csv
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
  profile)
    # where the time of one frame of flic evaluate goes: results/README.md section 10
    mkdir -p results/profile
    for m in flic0 flic14 bridge; do
      python scripts/profile_stages.py "$DATA" --method "$m" --setting ground \
        --ground-remover paper --repeat 3 > "results/profile/$m.txt"
    done
    ;;
  sensors)
    # the shared sensor recordings: results/sensors/README.md
    python scripts/sensors/check_formats.py --out results/sensors/formats_check.csv
    python scripts/sensors/read_timing.py --repeat 200 --out results/sensors/read_timing.csv
    # the ASCII PCD parsers side by side; PYARROW=<a pip --target folder with pyarrow> adds its
    # rows (pyarrow is no dependency of flic)
    PYTHONPATH=${PYARROW:-} python scripts/sensors/ascii_parsers.py --repeat 100 --core 1
    os2=$SENSORS/ouster/OS-2-128-U1_v2.3.0_1024x10.pcap
    fresh results/sensors/benchmark_os2_128
    taskset -c 0 flic benchmark "$os2" --methods flic0,flic14,bridge,bogoslavskyi --repeat 50 \
      --rounds 3 --out results/sensors/benchmark_os2_128
    keep results/sensors/benchmark_os2_128 environment.json frames.csv runtime.png summary.csv
    tmp=$(mktemp -d)
    flic segment "$os2" --method flic14 --render 0 --out "$tmp/seg"
    fresh results/sensors/segment_os2_128
    mkdir -p results/sensors/segment_os2_128
    cp "$tmp"/seg/render_*.png "$tmp"/seg/views_*.png results/sensors/segment_os2_128/
    # every other recording with the default methods, one table
    for rec in ouster/OS-1-64_1024x10_fw20.pcap ouster/OS-2-128-U1_v2.3.0_1024x10.pcap \
      velodyne/vlp16_velodyne_example.pcap velodyne/nebula_vlp16/1673400472138016708.pcd \
      pcd/robosense_helios16p_1691031766781547066.pcd \
      nuscenes/n015-2018-07-24-11-22-45+0800__LIDAR_TOP__1532402927647951.pcd.bin; do
      taskset -c 1 flic benchmark "$SENSORS/$rec" --repeat 20 --no-plots --out "$tmp/$(basename "$rec")"
    done
    python - "$tmp" results/sensors/benchmark_all.csv <<'PY'
import sys
from pathlib import Path

import pandas as pd

parts = []
for folder in sorted(p for p in Path(sys.argv[1]).iterdir() if (p / "summary.csv").exists()):
    df = pd.read_csv(folder / "summary.csv")
    df.insert(0, "recording", folder.name)
    parts.append(df[["recording", "method", "kind", "frames", "median_ms", "hz_median",
                     "points_median", "clusters_median"]])
pd.concat(parts).to_csv(sys.argv[2], index=False)
PY
    rm -rf "$tmp"
    ;;
  sensors-synthetic)
    # the synthetic street as each sensor profile sees them: results/sensors-synthetic/README.md.
    # The two configs it reads stay; everything it writes is rewritten whole.
    out=results/sensors-synthetic
    keep "$out" README.md bridge-defaults.toml sweep-bridge
    keep "$out/sweep-bridge" bridge-sweep.toml
    # every method on 10 frames of every profile; the VLP-16 also with Bridge's HDL-64E values
    python scripts/sensors_study.py profiles --frames 10 --out "$out" --work "$TMP/sensors" \
      --sensors vlp32c,hdl32e,hdl64e,os1-64,os1-128,os2-128
    python scripts/sensors_study.py profiles --frames 10 --out "$out" --work "$TMP/sensors" \
      --sensors vlp16 --extra-config "$out/bridge-defaults.toml" \
      --methods bogoslavskyi,flic0,flic1,flic6,flic14,flic1n,flic6n,flic14n,bridge,bridge-defaults,dbscan,euclidean,slr,cvc,alpine-agnostic
    python scripts/sensors_study.py links --work "$TMP/sensors" --frames 10 --out "$out/vertical_links.csv"
    # Bridge's grid on the two sparsest profiles: what its derived values rest on
    variants=$(python -c "import tomllib; print(','.join(tomllib.load(open('$out/sweep-bridge/bridge-sweep.toml', 'rb'))['methods']))")
    python scripts/sensors_study.py profiles --frames 10 --sensors vlp16,hdl32e \
      --methods "bridge,$variants" --extra-config "$out/sweep-bridge/bridge-sweep.toml" \
      --out "$out/sweep-bridge" --work "$TMP/sensors"
    # the ground setting with flic's own remover
    python scripts/sensors_study.py profiles --frames 10 --methods flic0,flic14,bridge \
      --ground-remover column --out "$out/ground-column" --work "$TMP/sensors"
    # 20 frames: the paired table (summary.csv), column's run limits, the MCs in degrees
    python scripts/sensors_study.py profiles --frames 20 --methods flic0,flic1,flic6,flic14,bridge,dbscan \
      --out "$out/derived-20frames" --work "$TMP/sensors-20"
    python scripts/sensors_study.py ground-column --frames 20 --work "$TMP/sensors-20" \
      --out "$out/ground-column/before_after.csv"
    python scripts/sensors_study.py mc-degrees --frames 20 --work "$TMP/sensors-20" \
      --out "$out/mc-degrees"
    python scripts/sensors_study.py links --work "$TMP/sensors-20" --frames 20 \
      --out "$TMP/vertical_links20.csv" --mc "$out/mc_links.csv"
    # what every shared recording derives
    python scripts/sensors_study.py recordings
    ;;
  bags)
    # ROS bags: docs/ros.md
    NUMBA_NUM_THREADS=1 taskset -c 0 python scripts/bags/cloud_speed.py --repeat 300 \
      > "$TMP/cloud_speed.txt"
    { echo "# command: NUMBA_NUM_THREADS=1 taskset -c 0 python scripts/bags/cloud_speed.py --repeat 300"
      cat "$TMP/cloud_speed.txt"; } > results/bags/cloud_speed.txt
    python scripts/bags/bag_memory.py --lengths 20,2000 --out results/bags/memory.csv
    bag=$TMP/vlp16-200
    rm -rf "$bag" "$TMP/latency"
    python -c "import sys; from pathlib import Path; sys.path.insert(0, 'tests'); \
from bagtools import cycled_vlp16_bag; cycled_vlp16_bag(Path('../shared/data'), Path('$bag'), 200)"
    NUMBA_NUM_THREADS=1 taskset -c 0 flic benchmark "$bag" --methods flic14,bogoslavskyi,bridge \
      --no-plots --out "$TMP/latency"
    cp "$TMP/latency/latency.csv" results/bags/latency_vlp16_200.csv
    ;;
  ouster-sdk)
    if [ -z "${OUSTER_PY:-}" ]; then
      skip "set OUSTER_PY to a Python with ouster-sdk installed"
      continue
    fi
    python scripts/sensors/ouster_sdk_comparison.py --sdk-python "$OUSTER_PY"
    ;;
  peers)
    # the field's clusterers (SLR, CVC, ALPINE, HDBSCAN, Euclidean) and "which clusterer?":
    # docs/peers.md, results/peers/sweeps/README.md
    bash scripts/peers_which_clusterer.sh "$DATA" results/peers "$JOBS"
    sample "$TMP/sample-seed0" 20 0
    bash scripts/peers_sweeps.sh "$DATA" "$TMP/sample-seed0/semantickitti" "$JOBS"
    # ALPINE's k, with and without box splitting (docs/peers.md)
    variants=alpine,alpine-nosplit,alpine-k32,alpine-k32-nosplit,alpine-k64,alpine-k64-nosplit
    fresh results/peers/alpine-k
    for name in kitti sample0; do
      data=$DATA
      [ "$name" = sample0 ] && data=$TMP/sample-seed0/semantickitti
      flic evaluate "$data" --config configs/alpine-k.toml --setting no-ground --methods "$variants" \
        --jobs "$JOBS" --out "results/peers/alpine-k/$name"
      keep "results/peers/alpine-k/$name" table.csv by_class.csv run.json
    done
    ;;
  peers-fidelity)
    if [ -z "${FLIC_REF:-}" ]; then
      skip "set FLIC_REF to the references built by scripts/peers_fidelity.sh"
      continue
    fi
    python scripts/peers_study.py clusterers "$DATA" results/peers/fidelity
    python scripts/peers_study.py ref-diff "$DATA" > results/peers/fidelity/ref_diff.txt
    python scripts/peers_study.py euclidean "$DATA" results/peers/fidelity \
      "$TMP/sample-seed0/semantickitti" 3
    python scripts/peers_study.py ablation "$DATA" results/peers/fidelity --every 5
    ;;
  cpp)
    # their C++ against flic, alternating in one session, on both logs; their ground masks
    if [ -z "${DC:-}" ]; then
      skip "set DC to a PRBonn/depth_clustering checkout"
      continue
    fi
    synthetic_log
    kitti_log
    bash scripts/depth_clustering/compare.sh "$DC" "$LOG/moosmann" results/benchmark/cpp-comparison
    bash scripts/depth_clustering/compare.sh "$DC" "$KLOG" \
      results/benchmark/cpp-comparison-kitti-as-moosmann
    S=$TMP/sample-100
    test -d "$S/moosmann" || flic sample "$S" --frames 100
    rm -rf "$TMP/masks-s" "$TMP/masks-k"
    bash scripts/depth_clustering/time_cpp.sh "$DC" "$S/moosmann" dump "$TMP/masks-s"
    python scripts/bogoslavskyi_fidelity.py "$S/moosmann" "$TMP/masks-s" \
      --out results/ground/bogoslavskyi_fidelity.csv
    bash scripts/depth_clustering/time_cpp.sh "$DC" "$KLOG" dump "$TMP/masks-k"
    python scripts/bogoslavskyi_fidelity.py "$KLOG" "$TMP/masks-k" \
      --out results/ground/bogoslavskyi_fidelity_kitti_as_moosmann.csv
    ;;
  panoptic)
    # semantic-kitti-api's evaluate_panoptic.py on flic's predictions: results/panoptic/README.md
    if [ -z "${SKAPI:-}" ]; then
      skip "set SKAPI to a PRBonn/semantic-kitti-api checkout"
      continue
    fi
    tmp=$(mktemp -d)
    flic evaluate "$DATA" --methods flic14,bridge --setting no-ground --semantics oracle \
      --jobs "$JOBS" --out "$tmp/ev"
    cp "$tmp/ev/panoptic.csv" "$tmp/ev/run.json" results/panoptic/
    data=$(realpath "$DATA")
    python -c "import yaml; d = yaml.safe_load(open('$SKAPI/config/semantic-kitti.yaml')); \
d['split']['valid'] = [0, 1, 3, 4, 8]; yaml.safe_dump(d, open('$tmp/sk.yaml', 'w'))"
    for m in flic14 bridge; do
      flic segment "$DATA" --method "$m" --semantics oracle --out "$tmp/$m"
      (cd "$SKAPI" && python evaluate_panoptic.py --dataset "$data" --predictions "$tmp/$m" \
        --split valid --data_cfg "$tmp/sk.yaml" --output "$tmp/$m")
      cp "$tmp/$m/scores.txt" "results/panoptic/semantic-kitti-api_scores_$m.txt"
    done
    rm -rf "$tmp"
    ;;
  *)
    echo "unknown step $step" >&2
    exit 2
    ;;
  esac
  step_log done
done
