#!/usr/bin/env bash
# Where the time of `photopose bundle` goes on issue 10's block, which solver settings win, and how
# time and memory grow with the block (docs/performance.md, "Bundle adjustment at scale").
#
#   tools/benchmarks/bundle_scaling.sh variants   # the settings compared on the 1000-image block
#   tools/benchmarks/bundle_scaling.sh growth     # 100, 300, 1000 and 3000 images, default settings
#   tools/benchmarks/bundle_scaling.sh statistics # 100, 300, 1000 (SIZES=...) images with
#                                                 # --statistics=full and none: their time and memory
#   tools/benchmarks/bundle_scaling.sh all
#
# SOLVER=taylor runs `--solver=taylor` instead of the default (Ceres); its labels end in _taylor.
#
# Every run is a whole `photopose bundle --colmap_model` process on a block written by
# `photopose simulate --scenario=block --benchmark_block --colmap` (its perturbed start, a relative
# block as COLMAP adjusts it, every observation kept), timed by /usr/bin/time (wall, peak resident
# memory). Per iteration it takes from photopose's progress lines the linear-solve and iteration
# times, and from Ceres' own timers (GLOG_v=3: SchurComplementSolver::Solve) the Schur
# elimination, the factorisation of the reduced camera system (ReducedSolve) and the
# back-substitution. Iterative solvers have no such split. Work goes to ${WORK:-build/bundle_scaling}.
# Run it on an otherwise idle machine: the figures are wall times.
set -euo pipefail
cd "$(dirname "$0")/../.."
PHOTOPOSE=${PHOTOPOSE:-build/photopose}
WORK=${WORK:-build/bundle_scaling}
MODE=${1:-all}
mkdir -p "$WORK"

block() {  # block NAME LINES IMAGES_PER_LINE
  if [ ! -f "$WORK/$1/colmap/images.txt" ]; then
    "$PHOTOPOSE" simulate --scenario=block --benchmark_block --lines="$2" --images_per_line="$3" \
      --colmap --out_dir="$WORK/$1" >/dev/null
  fi
}

SOLVER=${SOLVER:-}
SUFFIX=${SOLVER:+_$SOLVER}

run() {  # run LABEL BLOCK [flags...]: one whole process
  local label=$1$SUFFIX name=$2
  shift 2
  [ -z "$SOLVER" ] || set -- "$@" --solver="$SOLVER"
  echo "bundle_scaling: $label on $name" >&2
  rm -rf "$WORK/out_$label" && mkdir -p "$WORK/out_$label"
  set +e
  GLOG_minloglevel=0 GLOG_v=3 /usr/bin/time -v -o "$WORK/$label.time" "$PHOTOPOSE" bundle \
    --colmap_model="$WORK/$name/colmap" --out_colmap="$WORK/out_$label" --rejection_threshold=0 \
    --report="$WORK/$label.json" "$@" > "$WORK/$label.log" 2>&1
  echo "$?" > "$WORK/$label.exit"
  set -e
}

if [ "$MODE" = variants ] || [ "$MODE" = all ]; then
  block b1000 25 40
  run default b1000
  run threads1 b1000 --threads=1
  run autodiff b1000 --jacobian=autodiff
  run fixed_gauge b1000 --relative_gauge=fixed --max_iterations=10
  run iterative_jacobi b1000 --linear_solver=iterative_schur_jacobi --max_iterations=30
  run iterative_cluster b1000 --linear_solver=iterative_schur_cluster_jacobi --max_iterations=30
fi
if [ "$MODE" = growth ] || [ "$MODE" = all ]; then
  block b100 10 10
  block b300 15 20
  block b1000 25 40
  block b3000 50 60
  for n in 100 300 1000 3000; do run "growth$n" "b$n"; done
fi
if [ "$MODE" = statistics ]; then
  # The statistics (selected inversion, redundancy numbers, reliability) beside the adjustment:
  # the same block with them (full) and without (none); the adjustment's peak memory is none's.
  for n in ${SIZES:-100 300 1000}; do
    case $n in 100) block b100 10 10 ;; 300) block b300 15 20 ;; 1000) block b1000 25 40 ;;
      3000) block b3000 50 60 ;; esac
    run "stats_full$n" "b$n" --statistics=full
    run "stats_none$n" "b$n" --statistics=none
  done
  SUFFIX=$SUFFIX python3 - "$WORK" <<'EOF2'
import json, os, re, sys
work = sys.argv[1]
def peak(label):
    text = open(os.path.join(work, label + ".time")).read()
    return int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024
print("| images | marks | adjustment (s) | statistics (s) | of which factorisation / selected inversion (s) "
      "| inverse entries | peak with / without statistics (MiB) | ratio |")
print("|" + "---|" * 8)
for n in os.environ.get("SIZES", "100 300 1000").split():
    suffix = os.environ.get("SUFFIX", "")
    if not os.path.exists(os.path.join(work, f"stats_full{n}{suffix}.json")):
        continue
    full = json.load(open(os.path.join(work, f"stats_full{n}{suffix}.json")))["summary"]
    none = json.load(open(os.path.join(work, f"stats_none{n}{suffix}.json")))["summary"]
    st = full["statistics"]
    adjustment = none["time_seconds"] - none["statistics_seconds"]
    with_stats, without = peak(f"stats_full{n}{suffix}"), peak(f"stats_none{n}{suffix}")
    print(f"| {n} | {full['num_marks']} | {adjustment:.3g} | {full['statistics_seconds']:.3g} "
          f"| {st['factorization_seconds']:.3g} / {st['inversion_seconds']:.3g} | {st['inverse_entries']} "
          f"| {with_stats:.0f} / {without:.0f} | {with_stats / without:.2f} |")
EOF2
  exit 0
fi

python3 - "$WORK" <<'EOF'
import glob, json, os, re, sys
work = sys.argv[1]

def usage(path):
    text = open(path).read()
    h, m, s = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", text).groups()
    wall = (int(h) if h else 0) * 3600 + int(m) * 60 + float(s)
    return wall, int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024

def mean(values):
    return sum(values) / len(values) if values else float("nan")

rows = []
for time_file in sorted(glob.glob(os.path.join(work, "*.time")), key=os.path.getmtime):
    label = os.path.basename(time_file)[:-5]
    wall, peak = usage(time_file)
    log = open(os.path.join(work, label + ".log")).read()
    report = json.load(open(os.path.join(work, label + ".json")))
    s = report["summary"]
    t = s.get("time_breakdown", {})
    # Progress lines: "solve A of B s" per iteration (iteration 0 is the first evaluation).
    steps = [(float(a), float(b)) for it, a, b in
             re.findall(r"iteration +(\d+):.* solve ([\d.]+) of ([\d.]+) s", log) if int(it) > 0]
    # Ceres' timers per linear solve (the first Setup includes the symbolic analysis).
    def events(name):
        return [float(v) for v in re.findall(r"^ +%s : +([\d.]+)" % name, log, re.M)]
    setup, eliminate, reduced, back = (events(n) for n in
                                       ("Setup", "Eliminate", "ReducedSolve", "BackSubstitute"))
    rows.append((label, s["num_images"], s["num_marks"], s["termination"], s["iterations"],
                 s["final_cost"], wall, peak, mean([b for _, b in steps]),
                 mean([a for a, _ in steps]), mean(eliminate), mean(reduced), mean(back),
                 t.get("problem_build_seconds"), t.get("solver_preprocessing_seconds"),
                 t.get("residual_evaluation_seconds"), t.get("jacobian_evaluation_seconds"),
                 t.get("linear_solver_seconds"), t.get("schur_structure")))

print("| run | images | marks | termination | iterations | final cost (px²) | wall (s) | peak (MiB) "
      "| s per iteration | linear solve | Schur elimination | factorisation | back-subst. "
      "| problem build | Ceres preprocessing | residuals | Jacobians | linear solves | Schur structure |")
print("|" + "---|" * 19)
fmt = lambda v: "—" if v is None or v != v else (f"{v:.3g}" if isinstance(v, float) else str(v))
for r in rows:
    print("| " + " | ".join(fmt(v) for v in r) + " |")
EOF
