#!/usr/bin/env bash
# photopose bundle against COLMAP's bundle_adjuster on the same simulated block, in one run
# (docs/performance.md, "Bundle adjustment against COLMAP").
#
#   tools/benchmarks/colmap_bundle_comparison.sh [LINES IMAGES_PER_LINE TIE_POINTS]
#
# Default: issue 10's block (25 x 40 images, 120 000 tie points, ~1.7 million marks), written by
# `photopose simulate --scenario=block --benchmark_block --colmap` with its perturbed start. Both
# programs adjust that COLMAP model with the intrinsics fixed and every observation kept; each is timed as a whole process
# (wall time and peak memory from /usr/bin/time). COLMAP's own iteration log gives the time at
# which it first reached the cost at which photopose stopped. photopose runs twice: the Ceres path
# (the default) and the hand-written Taylor solver (--solver=taylor). Needs the Debian packages colmap and
# time; the work goes to ${WORK:-build/colmap_comparison}.
set -euo pipefail
cd "$(dirname "$0")/../.."
PHOTOPOSE=${PHOTOPOSE:-build/photopose}
WORK=${WORK:-build/colmap_comparison}
rm -rf "$WORK" && mkdir -p "$WORK"

if [ $# -ge 3 ]; then
  "$PHOTOPOSE" simulate --scenario=block --lines="$1" --images_per_line="$2" --tie_points="$3" \
    --colmap --out_dir="$WORK/block" >/dev/null
  label="$1 x $2 images, $3 tie points"
else
  "$PHOTOPOSE" simulate --scenario=block --benchmark_block --colmap --out_dir="$WORK/block" >/dev/null
  label="issue 10's block"
fi
mkdir -p "$WORK/colmap_out" "$WORK/photopose_out" "$WORK/taylor_out"
/usr/bin/time -v -o "$WORK/colmap.time" colmap bundle_adjuster \
  --input_path "$WORK/block/colmap" --output_path "$WORK/colmap_out" \
  --BundleAdjustment.refine_focal_length 0 --BundleAdjustment.refine_principal_point 0 \
  --BundleAdjustment.refine_extra_params 0 > "$WORK/colmap.log" 2>&1
/usr/bin/time -v -o "$WORK/photopose.time" "$PHOTOPOSE" bundle \
  --colmap_model="$WORK/block/colmap" --out_colmap="$WORK/photopose_out" \
  --rejection_threshold=0 --report="$WORK/photopose_report.json" > "$WORK/photopose.log" 2>&1
# The hand-written Taylor solver on the same model, same settings (issue 23).
/usr/bin/time -v -o "$WORK/taylor.time" "$PHOTOPOSE" bundle --solver=taylor \
  --colmap_model="$WORK/block/colmap" --out_colmap="$WORK/taylor_out" \
  --rejection_threshold=0 --report="$WORK/taylor_report.json" > "$WORK/taylor.log" 2>&1

python3 - "$WORK" "$label" <<'EOF'
import json, re, sys
work, label = sys.argv[1], sys.argv[2]

def usage(path):
    text = open(path).read()
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", text)
    h, m, s = wall.groups()
    seconds = (int(h) if h else 0) * 3600 + int(m) * 60 + float(s)
    peak_mb = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024
    return seconds, peak_mb

colmap_s, colmap_mb = usage(work + "/colmap.time")
ours_s, ours_mb = usage(work + "/photopose.time")
report = json.load(open(work + "/photopose_report.json"))
ours_cost = report["summary"]["final_cost"]
ours_iterations = report["summary"]["iterations"]
marks = report["summary"]["num_marks"]
# COLMAP's Ceres iteration log: "iter cost cost_change |gradient| |step| tr_ratio tr_radius
# ls_iter iter_time total_time".
log = open(work + "/colmap.log").read()
iterations = [(int(a), float(b), float(c)) for a, b, c in
              re.findall(r"^\s*(\d+)\s+([-+0-9.e]+)\s+[-+0-9.e]+\s+[-+0-9.e]+\s+[-+0-9.e]+\s+"
                         r"[-+0-9.e]+\s+[-+0-9.e]+\s+\d+\s+[-+0-9.e]+\s+([-+0-9.e]+)\s*$",
                         log, re.M)]
reached = [t for _, cost, t in iterations if cost <= ours_cost]
colmap_final = iterations[-1][1] if iterations else float("nan")
to_same = reached[0] if reached else colmap_s
print(f"block: {label}, {marks} marks")
print(f"photopose bundle: {ours_s:.1f} s wall, peak {ours_mb:.0f} MB, {ours_iterations} iterations, "
      f"final cost {ours_cost:.6g} px^2")
print(f"colmap bundle_adjuster: {colmap_s:.1f} s wall, peak {colmap_mb:.0f} MB, "
      f"{len(iterations) - 1} iterations, final cost {colmap_final:.6g} px^2; "
      f"time to photopose's cost: {to_same:.1f} s" + ("" if reached else " (never reached: whole time)"))
t = report["summary"]["time_breakdown"]
setup = t["read_seconds"] + t["setup_seconds"]
print(f"photopose steps: read {t['read_seconds']:.1f} s, plan {t['plan_seconds']:.1f} s, problem "
      f"{t['problem_build_seconds']:.1f} s, Ceres preprocessing {t['solver_preprocessing_seconds']:.1f} s, "
      f"rounds {', '.join(f'{r:.1f}' for r in t['round_seconds'])} s, statistics "
      f"{t['statistics_seconds']:.1f} s, the rest (write, exit) "
      f"{ours_s - t['read_seconds'] - t['initialization_seconds'] - report['summary']['time_seconds']:.1f} s; "
      f"setup (read, plan, problem, preprocessing) {setup:.1f} s = {100 * setup / ours_s:.0f} % of the run")
print(f"ratio photopose / colmap-to-same-cost: {ours_s / to_same:.3f}; final cost ratio "
      f"photopose / colmap: {ours_cost / colmap_final:.6f}; memory ratio {ours_mb / colmap_mb:.2f}")
taylor_s, taylor_mb = usage(work + "/taylor.time")
taylor = json.load(open(work + "/taylor_report.json"))["summary"]
tt = taylor["time_breakdown"]
print(f"photopose bundle --solver=taylor: {taylor_s:.1f} s wall, peak {taylor_mb:.0f} MB, "
      f"{taylor['iterations']} iterations, final cost {taylor['final_cost']:.10g} px^2 "
      f"(relative difference to the Ceres path {abs(taylor['final_cost'] - ours_cost) / ours_cost:.1e}), "
      f"statistics {tt['statistics_seconds']:.1f} s; ratio taylor / colmap-to-same-cost "
      f"{taylor_s / to_same:.3f}, taylor / ceres path {taylor_s / ours_s:.3f}, "
      f"memory ratio to colmap {taylor_mb / colmap_mb:.2f}")
EOF
