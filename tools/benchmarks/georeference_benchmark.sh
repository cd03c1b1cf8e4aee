#!/usr/bin/env bash
# What georeferencing costs on top of the same bundle adjustment (docs/performance.md,
# "Georeferencing"). The block: `photopose simulate --scenario=block --benchmark_block --colmap`
# (1000 images, ~1.7 million marks by default; LINES / IMAGES_PER_LINE resize it) with its GNSS
# positions (frames.csv, 3 cm / 6 cm stated). Two whole processes, each timed by /usr/bin/time:
#   tables:  bundle --cameras --marks --frames         positions as priors, no CRS anywhere
#   georef:  bundle --colmap_model --geo=geo.txt       the same positions as an ODM geo.txt in
#            EPSG:32632: PROJ into the local frame, matching, similarity, the same adjustment,
#            the outputs back in EPSG:32632
# Both write --out and --out_points. Work goes to ${WORK:-build/georeference_benchmark}. Run it on an
# otherwise idle machine: the figures are wall times.
set -euo pipefail
cd "$(dirname "$0")/../.."
PHOTOPOSE=${PHOTOPOSE:-build/photopose}
WORK=${WORK:-build/georeference_benchmark}
LINES=${LINES:-25}
IMAGES_PER_LINE=${IMAGES_PER_LINE:-40}
mkdir -p "$WORK"
block="$WORK/block_${LINES}x${IMAGES_PER_LINE}"
if [ ! -f "$block/colmap/images.txt" ]; then
  "$PHOTOPOSE" simulate --scenario=block --benchmark_block --lines="$LINES" \
    --images_per_line="$IMAGES_PER_LINE" --colmap --out_dir="$block" >/dev/null
fi
python3 - "$block/frames.csv" "$WORK/geo.txt" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
with open(sys.argv[2], "w") as out:
    out.write("EPSG:32632\n")
    for r in rows:
        out.write("%s %s %s %s 0 0 0 %s %s\n" % (r["Raster"], r["PerspectiveX"], r["PerspectiveY"],
                  r["PerspectiveZ"], r["AccuracyX"], r["AccuracyZ"]))
PY
run() {  # run LABEL flags...
  local label=$1
  shift
  echo "georeference_benchmark: $label" >&2
  /usr/bin/time -v -o "$WORK/$label.time" "$PHOTOPOSE" bundle --rejection_threshold=0 \
    --out="$WORK/$label.frames.csv" --out_points="$WORK/$label.points.csv" \
    --report="$WORK/$label.json" "$@" > "$WORK/$label.log" 2> "$WORK/$label.err"
}
run tables --cameras="$block/cameras.csv" --marks="$block/marks.csv" --frames="$block/frames.csv"
run georef --colmap_model="$block/colmap" --geo="$WORK/geo.txt"
wall() { awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, t, ":"); s = 0; for (i = 1; i <= n; ++i) s = s * 60 + t[i]; print s}' "$1"; }
rss() { awk -F': ' '/Maximum resident set size/ {printf "%.0f", $2 / 1024}' "$1"; }
t_tables=$(wall "$WORK/tables.time")
t_georef=$(wall "$WORK/georef.time")
echo "| run | wall (s) | peak RSS (MiB) |"
echo "|---|---|---|"
echo "| tables (no CRS) | $t_tables | $(rss "$WORK/tables.time") |"
echo "| georef (EPSG:32632 via the local frame) | $t_georef | $(rss "$WORK/georef.time") |"
python3 -c "print('georef / tables wall: %.3f' % ($t_georef / $t_tables))"
grep "georeference:" "$WORK/georef.err" || true
python3 - "$WORK/georef.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
g = r["georeference"]
print("georef report: prepare %.2f s, evaluate %.2f s, bundle %.1f s, positions matched %d, similarity inliers %d of %d"
      % (g["time_seconds"]["prepare"], g["time_seconds"]["evaluate"], r["summary"]["time_seconds"],
         g["positions_matched"], g["similarity"]["num_inliers"], g["similarity"]["num_pairs"]))
PY
