#!/usr/bin/env python3
"""What merging sub-blocks loses against one global adjustment (docs/scaling.md).

    PHOTOPOSE=build/photopose python3 tools/benchmarks/partition_experiment.py \
        [--lines=8 --images_per_line=25 --tie_points=24000] [--partitions=2:1,4:1] \
        [--work_dir=build/partition_experiment] [--csv=FILE]

On one simulated block (control points, check points, GNSS centres; the truth kept in
WORK/block/truth) it runs, each as its own `photopose bundle` process:

  1. the global adjustment from the simulator's start (cold): the reference;
  2. for every partition K:H, the block cut by flight lines into K sub-blocks of contiguous lines
     (the "core" lines of each sub-block), each widened by H lines into each neighbour (the halo:
     neighbouring sub-blocks share 2H lines); every sub-block's tables are written (its frames
     rows, its marks, its control and check points) and the sub-blocks adjusted as separate
     processes, --jobs at a time (default 2: this machine has 2 cores);
  3. the merge, two ways. A: each camera from the sub-block whose core holds its line (its
     "owner"), each tie and check point averaged over the sub-blocks that hold it. B (the start of
     step 4): each camera averaged over the sub-blocks that hold it (centres averaged, rotations
     by their normalised quaternion sum), each point from the sub-block in which it has the most
     rays;
  4. the final global adjustment started from the merged solution (merged angles, merged tie points
     as approximate values), against the cold start of step 1.

Every figure is measured against the simulator's truth: camera-centre RMSE, attitude RMSE (the angle
of R_est R_true^T), tie-point RMSE, and the check-point RMSE against the surveyed coordinates (as
the bundle report computes it); the seam is the discrepancy between sub-blocks in their overlap.
Prints a table and writes a CSV. Python 3 standard library only. Flight lines are read from the
simulator's image names (L<line>_<image>).

Every adjustment keeps all marks (--rejection_threshold=0: the simulated block has no blunders,
and the same observations must enter every run) and skips the covariances
(--statistics=none: only the adjustment is timed), one thread per process.
"""

import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import time

ARCSEC = 180.0 / math.pi * 3600.0


# ---------------------------------------------------------------- rotations (docs/conventions.md)

def rot_rxryrz(omega_deg, phi_deg, kappa_deg):
    """R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa), the frames tables' rxryrz convention."""
    o, p, k = (math.radians(a) for a in (omega_deg, phi_deg, kappa_deg))
    co, so, cp, sp, ck, sk = math.cos(o), math.sin(o), math.cos(p), math.sin(p), math.cos(k), math.sin(k)
    rx = [[1, 0, 0], [0, co, -so], [0, so, co]]
    ry = [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]
    rz = [[ck, -sk, 0], [sk, ck, 0], [0, 0, 1]]
    return matmul(matmul(rx, ry), rz)


def angles_rxryrz(r):
    """The inverse of rot_rxryrz (away from phi = +-90 degrees)."""
    phi = math.asin(max(-1.0, min(1.0, r[0][2])))
    omega = math.atan2(-r[1][2], r[2][2])
    kappa = math.atan2(-r[0][1], r[0][0])
    return tuple(math.degrees(a) for a in (omega, phi, kappa))


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a):
    return [[a[j][i] for j in range(3)] for i in range(3)]


def rotation_angle(a, b):
    """Angle (rad) of the rotation a b^T."""
    m = matmul(a, transpose(b))
    c = (m[0][0] + m[1][1] + m[2][2] - 1.0) / 2.0
    return math.acos(max(-1.0, min(1.0, c)))


def quaternion(r):
    """Unit quaternion (w, x, y, z) of a rotation matrix."""
    t = r[0][0] + r[1][1] + r[2][2]
    if t > 0:
        s = math.sqrt(t + 1.0) * 2
        q = (0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s)
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2
        q = ((r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s)
    elif r[1][1] > r[2][2]:
        s = math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2
        q = ((r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s)
    else:
        s = math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2
        q = ((r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s)
    return q


def matrix_from_quaternion(q):
    n = math.sqrt(sum(c * c for c in q))
    w, x, y, z = (c / n for c in q)
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def mean_rotation(rs):
    """Average of nearby rotations: the normalised sum of their quaternions (signs aligned)."""
    qs = [quaternion(r) for r in rs]
    acc = [0.0] * 4
    for q in qs:
        sign = 1.0 if sum(a * b for a, b in zip(q, qs[0])) >= 0 else -1.0
        acc = [a + sign * b for a, b in zip(acc, q)]
    return matrix_from_quaternion(acc)


# ---------------------------------------------------------------- tables

def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def write_rows(path, fieldnames, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fieldnames, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def poses(path):
    """Raster -> (centre, R_camera_from_ground) of a frames table in rxryrz degrees."""
    out = {}
    for row in read_rows(path):
        c = tuple(float(row[k]) for k in ("PerspectiveX", "PerspectiveY", "PerspectiveZ"))
        out[row["Raster"]] = (c, rot_rxryrz(float(row["Omega"]), float(row["Phi"]), float(row["Kappa"])))
    return out


def positions(path, roles=None):
    """PointID -> position. In a `bundle --out_points` table the X, Y, Z of a check point are its
    surveyed coordinates; its intersection is X + ErrorX (etc.), and that is what is returned."""
    out = {}
    for row in read_rows(path):
        role = row.get("Role", "").lower()
        if roles is None or role in roles:
            p = [float(row[k]) for k in ("X", "Y", "Z")]
            if role == "check" and "ErrorX" in row:  # a bundle output, not the truth
                if not row["ErrorX"]:
                    continue  # not intersected: its X, Y, Z are the surveyed ones, not an estimate
                p = [p[i] + float(row["Error" + k]) for i, k in enumerate("XYZ")]
            out[row["PointID"]] = tuple(p)
    return out


def line_of(raster):
    m = re.match(r"L(\d+)_", raster)
    if not m:
        sys.exit(f"partition_experiment: image '{raster}' is not named L<line>_<image>")
    return int(m.group(1))


def rms(values):
    values = list(values)
    return math.sqrt(sum(v * v for v in values) / len(values)) if values else float("nan")


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


# ---------------------------------------------------------------- the convention, checked

def check_convention(block, truth_frames, truth_points, samples=200):
    """Projects true points through true frames (rxryrz, docs/conventions.md) and compares with
    the simulated marks: the frames tables this script writes use the same convention."""
    cam = read_rows(os.path.join(block, "cameras.csv"))[0]
    c = float(cam["FocalLength"])
    pix = float(cam["PixelSize"])
    ncol, nrow = float(cam["NColumns"]), float(cam["NRows"])
    worst, n = 0.0, 0
    with open(os.path.join(block, "marks.csv"), newline="") as f:
        for row in csv.DictReader(f):
            if n >= samples:
                break
            n += 1
            (x0, r), p = truth_frames[row["Raster"]], truth_points[row["PointID"]]
            d = [p[i] - x0[i] for i in range(3)]
            u, v, w = (sum(r[i][k] * d[k] for k in range(3)) for i in range(3))
            x, y = -c * u / w, -c * v / w  # film, micrometres, y up
            col, rw = ncol / 2 + x / pix, nrow / 2 - y / pix
            worst = max(worst, math.hypot(col - float(row["Column"]), rw - float(row["Row"])))
    for o, p, k in ((2.0, -3.0, 30.0), (0.7, 1.2, -178.0)):  # angles -> matrix -> angles
        back = angles_rxryrz(rot_rxryrz(o, p, k))
        if max(abs(x - y) for x, y in zip(back, (o, p, k))) > 1e-9:
            sys.exit(f"partition_experiment: rxryrz angles do not survive the round trip: {back}")
    example = rot_rxryrz(2.0, -3.0, 30.0)[0]  # docs/conventions.md, first row of R
    if max(abs(x - y) for x, y in zip(example, (0.864839, -0.499315, -0.052336))) > 1e-6:
        sys.exit(f"partition_experiment: rxryrz matrix differs from docs/conventions.md: {example}")
    if worst > 5.0:
        sys.exit(f"partition_experiment: true points miss their marks by {worst:.1f} px through "
                 "the true frames: the rotation convention assumed here (rxryrz) is wrong")
    return worst


# ---------------------------------------------------------------- processes

def bundle_args(photopose, tables, out, threads):
    return [photopose, "bundle", f"--cameras={tables['cameras']}", f"--marks={tables['marks']}",
            f"--points={tables['points']}", f"--frames={tables['frames']}",
            f"--out={out}/frames.csv", f"--out_points={out}/points.csv", f"--report={out}/report.json",
            "--rejection_threshold=0", "--statistics=none", f"--threads={threads}", "--quiet"]


# Runs argv[2:] and writes its peak resident memory (kB) and CPU seconds to argv[1]. On Linux a
# process's ru_maxrss includes the memory of the process it was forked from (exec keeps the
# larger), and this script holds the whole marks table: a small fresh interpreter in between keeps
# photopose's figure its own.
MEASURE = """import os, sys
pid = os.fork()
if pid == 0:
    os.execvp(sys.argv[2], sys.argv[2:])
_, status, usage = os.wait4(pid, 0)
with open(sys.argv[1], "w") as f:
    f.write(f"{usage.ru_maxrss} {usage.ru_utime + usage.ru_stime}")
sys.exit(os.waitstatus_to_exitcode(status))
"""


def run_jobs(jobs, parallel):
    """Runs (name, argv, log) jobs, `parallel` at a time. Returns name -> {wall_s, cpu_s, rss_mb}
    and the wall time of the whole phase."""
    pending, running, results = list(jobs), {}, {}
    phase_start = time.monotonic()
    while pending or running:
        while pending and len(running) < parallel:
            name, argv, log = pending.pop(0)
            with open(log, "w") as f:
                p = subprocess.Popen([sys.executable, "-c", MEASURE, log + ".usage"] + argv,
                                     stdout=f, stderr=subprocess.STDOUT)
            running[p.pid] = (name, p, time.monotonic(), log)
        pid, status, _ = os.wait4(-1, 0)
        if pid not in running:
            continue
        name, p, start, log = running.pop(pid)
        p.returncode = os.waitstatus_to_exitcode(status)
        if p.returncode != 0:
            with open(log) as f:
                sys.exit(f"partition_experiment: {name} exited {p.returncode}:\n{f.read()[-2000:]}")
        with open(log + ".usage") as f:
            rss_kb, cpu_s = f.read().split()
        results[name] = {"wall_s": time.monotonic() - start, "cpu_s": float(cpu_s),
                         "rss_mb": float(rss_kb) / 1024.0}
    return results, time.monotonic() - phase_start


def report(out):
    import json
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)


# ---------------------------------------------------------------- measures

def measure(frames, ties, checks, truth_frames, truth_points, surveyed):
    """Camera-centre RMSE (m), attitude RMSE (rad), tie RMSE against the truth (m), check RMSE
    against the surveyed coordinates (m, as the bundle report) for a solution."""
    return {
        "camera_rmse_m": rms(dist(c, truth_frames[k][0]) for k, (c, _) in frames.items()),
        "attitude_rms_rad": rms(rotation_angle(r, truth_frames[k][1]) for k, (_, r) in frames.items()),
        "tie_rmse_m": rms(dist(p, truth_points[k]) for k, p in ties.items()),
        "check_rmse_m": rms(dist(p, surveyed[k]) for k, p in checks.items()),
        "num_checks": len(checks),
    }


def partition(lines, k, halo):
    """K sub-blocks of contiguous flight lines: core lines and the core widened by `halo` lines
    into each neighbour."""
    n = len(lines)
    bounds = [round(i * n / k) for i in range(k + 1)]
    subs = []
    for i in range(k):
        core = lines[bounds[i]:bounds[i + 1]]
        lo, hi = max(0, bounds[i] - halo), min(n, bounds[i + 1] + halo)
        subs.append({"core": set(core), "lines": set(lines[lo:hi])})
    return subs


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--photopose", default=os.environ.get("PHOTOPOSE", "build/photopose"))
    ap.add_argument("--work_dir", default="build/partition_experiment")
    ap.add_argument("--csv", default="", help="default: WORK_DIR/partition_experiment.csv")
    ap.add_argument("--lines", type=int, default=8)
    ap.add_argument("--images_per_line", type=int, default=25)
    ap.add_argument("--tie_points", type=int, default=24000)
    ap.add_argument("--control_points", type=int, default=12)
    ap.add_argument("--check_points", type=int, default=30)
    ap.add_argument("--gnss_sigma", type=float, default=0.03)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--partitions", default="2:1,4:1",
                    help="comma list of K:H (K sub-blocks, H halo lines into each neighbour)")
    ap.add_argument("--jobs", type=int, default=2, help="sub-block processes at a time")
    ap.add_argument("--threads", type=int, default=1, help="--threads of every bundle process")
    return ap.parse_args()


class Block:
    """The simulated block: its tables, their rows, the truth, the flight lines."""


def simulate_block(a, work):
    """Simulates the block into WORK/block and reads it back (checking the rotation convention)."""
    b = Block()
    b.dir = os.path.join(work, "block")
    subprocess.run([a.photopose, "simulate", "--scenario=block", f"--lines={a.lines}",
                    f"--images_per_line={a.images_per_line}", f"--tie_points={a.tie_points}",
                    f"--control_points={a.control_points}", f"--check_points={a.check_points}",
                    f"--gnss_sigma={a.gnss_sigma}", f"--seed={a.seed}", f"--out_dir={b.dir}"],
                   check=True, stdout=subprocess.DEVNULL)
    b.tables = {k: os.path.join(b.dir, k + ".csv") for k in ("cameras", "marks", "points", "frames")}
    b.truth_frames = poses(os.path.join(b.dir, "truth", "frames.csv"))
    b.truth_points = positions(os.path.join(b.dir, "truth", "points.csv"))
    miss = check_convention(b.dir, b.truth_frames, b.truth_points)
    b.point_rows = read_rows(b.tables["points"])
    b.point_fields = list(b.point_rows[0].keys())
    b.surveyed = {r["PointID"]: tuple(float(r[k]) for k in "XYZ")
                  for r in b.point_rows if r["Role"].lower() == "check"}
    b.frame_rows = read_rows(b.tables["frames"])
    b.frame_fields = list(b.frame_rows[0].keys())
    with open(b.tables["marks"]) as f:
        b.marks_header = f.readline()
        marks = [(line.split(",", 2), line) for line in f]
    b.marks = [(fields[0], fields[1], line) for fields, line in marks]
    b.images = [r["Raster"] for r in b.frame_rows]
    b.lines = sorted({line_of(r) for r in b.images})
    print(f"block: {len(b.lines)} lines x {a.images_per_line} images, {a.tie_points} tie points, "
          f"{len(b.marks)} marks; true points meet their marks through the true rxryrz frames "
          f"within {miss:.2f} px", flush=True)
    return b


def add_row(rows, solution, k, halo, m, **extra):
    """One solution's row of the table; report_check_rmse_mm: the bundle report's own figure, a
    cross-check."""
    row = {"solution": solution, "K": k, "halo_lines": halo,
           "camera_rmse_mm": 1000 * m["camera_rmse_m"],
           "attitude_rms_arcsec": ARCSEC * m["attitude_rms_rad"],
           "check_rmse_mm": 1000 * m["check_rmse_m"], "tie_rmse_mm": 1000 * m["tie_rmse_m"]}
    row.update(extra)
    rows.append(row)


def measure_output(out, b):
    """measure() of the frames and points a bundle process wrote to `out`."""
    return measure(poses(os.path.join(out, "frames.csv")),
                   positions(os.path.join(out, "points.csv"), {"tie"}),
                   positions(os.path.join(out, "points.csv"), {"check"}),
                   b.truth_frames, b.truth_points, b.surveyed)


def run_global(a, work, b, rows):
    """1. The global adjustment, cold. Returns its frames and tie points."""
    gdir = os.path.join(work, "global")
    os.makedirs(gdir)
    res, _ = run_jobs([("global", bundle_args(a.photopose, b.tables, gdir, a.threads),
                        os.path.join(gdir, "log.txt"))], 1)
    grep = report(gdir)
    gframes = poses(os.path.join(gdir, "frames.csv"))
    gpoints = positions(os.path.join(gdir, "points.csv"), {"tie"})
    add_row(rows, "global (cold start)", 1, 0, measure_output(gdir, b),
            images_per_process=len(b.images), iterations=grep["summary"]["iterations"],
            adjust_s=grep["summary"]["time_seconds"], wall_s=res["global"]["wall_s"],
            peak_rss_mb=res["global"]["rss_mb"],
            report_check_rmse_mm=1000 * grep["check_rmse_m"]["total"],
            initial_cost=grep["summary"]["initial_cost"])
    return gframes, gpoints


def write_sub_block(a, b, sub, d):
    """Writes a sub-block's tables into `d` and returns its bundle job."""
    sub_images = {r for r in b.images if line_of(r) in sub["lines"]}
    sub["images"] = sub_images
    # A tie point goes in when three of the sub-block's images see it: two rays from the
    # start angles may miss each other by more than `bundle`'s initialisation accepts (3
    # degrees), and the run is refused; control points wherever one image sees them, check points
    # where two do (one ray intersects nothing: a sub-block cannot check it).
    seen = {}
    for raster, pid, _ in b.marks:
        if raster in sub_images:
            seen[pid] = seen.get(pid, 0) + 1
    role = {r["PointID"]: r["Role"].lower() for r in b.point_rows}
    keep = {p for p, n in seen.items()
            if n >= 3 or role.get(p) == "control" or (role.get(p) == "check" and n >= 2)}
    t = {"cameras": b.tables["cameras"]}
    for key in ("marks", "points", "frames"):
        t[key] = os.path.join(d, key + ".csv")
    with open(t["marks"], "w") as f:
        f.write(b.marks_header)
        f.writelines(line for raster, pid, line in b.marks if raster in sub_images and pid in keep)
    write_rows(t["points"], b.point_fields, [r for r in b.point_rows if r["PointID"] in keep])
    write_rows(t["frames"], b.frame_fields, [r for r in b.frame_rows if r["Raster"] in sub_images])
    return bundle_args(a.photopose, t, os.path.join(d, "out"), a.threads)


def adjust_sub_blocks(a, work, name, b, subs):
    """2. Every sub-block's tables written and adjusted, --jobs at a time. Returns the processes'
    figures, the phase's wall time and the time taken to write the tables."""
    t_split = time.monotonic()
    jobs = []
    for i, sub in enumerate(subs):
        d = os.path.join(work, name, f"sub{i + 1}")
        os.makedirs(d)
        sub["dir"] = d
        jobs.append((f"sub{i + 1}", write_sub_block(a, b, sub, d), os.path.join(d, "log.txt")))
        os.makedirs(os.path.join(d, "out"))
    split_s = time.monotonic() - t_split
    res, phase_wall = run_jobs(jobs, a.jobs)
    return res, phase_wall, split_s


def collect_estimates(subs):
    """Every sub-block's estimates: image -> [(sub-block, pose)], point -> [(rays, position)] for
    tie and check points, and each sub-block's iterations."""
    est_frames, est_ties, est_checks = {}, {}, {}
    sub_iters = []
    for i, sub in enumerate(subs):
        out = os.path.join(sub["dir"], "out")
        sub_iters.append(report(out)["summary"]["iterations"])
        for img, pose in poses(os.path.join(out, "frames.csv")).items():
            est_frames.setdefault(img, []).append((i, pose))
        rays = {r["PointID"]: int(r["NumObservations"]) for r in read_rows(os.path.join(out, "points.csv"))}
        for pid, p in positions(os.path.join(out, "points.csv"), {"tie"}).items():
            est_ties.setdefault(pid, []).append((rays[pid], p))
        for pid, p in positions(os.path.join(out, "points.csv"), {"check"}).items():
            est_checks.setdefault(pid, []).append((rays[pid], p))
    return est_frames, est_ties, est_checks, sub_iters


def merge(subs, est_frames, est_ties, est_checks):
    """3. The two merges: A (the owner's cameras, averaged points) and B (averaged cameras, points
    from the sub-block with the most rays), each as (frames, ties, checks)."""
    owner = {}
    for i, sub in enumerate(subs):
        for img in sub["images"]:
            if line_of(img) in sub["core"]:
                owner[img] = i
    owned = {img: next(p for j, p in ests if j == owner[img]) for img, ests in est_frames.items()}
    averaged = {img: (tuple(sum(p[0][c] for _, p in ests) / len(ests) for c in range(3)),
                      mean_rotation([p[1] for _, p in ests])) for img, ests in est_frames.items()}
    mean_pt = lambda ps: tuple(sum(p[c] for p in ps) / len(ps) for c in range(3))
    ties = {pid: mean_pt([p for _, p in ps]) for pid, ps in est_ties.items()}
    checks = {pid: mean_pt([p for _, p in ps]) for pid, ps in est_checks.items()}
    most_rays = lambda ps: max(ps, key=lambda e: e[0])[1]
    ties_b = {pid: most_rays(ps) for pid, ps in est_ties.items()}
    checks_b = {pid: most_rays(ps) for pid, ps in est_checks.items()}
    return (owned, ties, checks), (averaged, ties_b, checks_b)


def seam_figures(est_frames, est_ties):
    """The seam: sub-block against sub-block where they overlap (every pair of estimates)."""
    seam_c, seam_r, seam_t = [], [], []
    for ests in est_frames.values():
        for x in range(len(ests)):
            for y in range(x + 1, len(ests)):
                (c1, r1), (c2, r2) = ests[x][1], ests[y][1]
                seam_c.append(dist(c1, c2))
                seam_r.append(rotation_angle(r1, r2))
    for ps in est_ties.values():
        for x in range(len(ps)):
            for y in range(x + 1, len(ps)):
                seam_t.append(dist(ps[x][1], ps[y][1]))
    return {"seam_centre_rms_mm": 1000 * rms(seam_c), "seam_centre_max_mm": 1000 * max(seam_c, default=0),
            "seam_attitude_rms_arcsec": ARCSEC * rms(seam_r),
            "seam_tie_rms_mm": 1000 * rms(seam_t), "seam_tie_max_mm": 1000 * max(seam_t, default=0),
            "overlap_images": sum(len(e) > 1 for e in est_frames.values()),
            "overlap_ties": sum(len(p) > 1 for p in est_ties.values())}


def final_global(a, work, name, b, averaged, ties_b):
    """4. The final global adjustment from merge B: merged angles (the centres stay the GNSS
    measurements: PerspectiveX/Y/Z is both the prior and the start), merged tie points as
    approximate values (Role tie). Returns its output folder and the process's figures."""
    fdir = os.path.join(work, name, "final")
    os.makedirs(os.path.join(fdir, "out"))
    warm = {"cameras": b.tables["cameras"], "marks": b.tables["marks"],
            "points": os.path.join(fdir, "points.csv"), "frames": os.path.join(fdir, "frames.csv")}
    warm_frames = []
    for r in b.frame_rows:
        r = dict(r)
        r["Omega"], r["Phi"], r["Kappa"] = (repr(v) for v in angles_rxryrz(averaged[r["Raster"]][1]))
        warm_frames.append(r)
    write_rows(warm["frames"], b.frame_fields, warm_frames)
    tie_rows = [{**{f: "" for f in b.point_fields}, "PointID": pid, "X": repr(p[0]), "Y": repr(p[1]),
                 "Z": repr(p[2]), "Role": "tie"} for pid, p in ties_b.items()]
    write_rows(warm["points"], b.point_fields, b.point_rows + tie_rows)
    out = os.path.join(fdir, "out")
    res, _ = run_jobs([("final", bundle_args(a.photopose, warm, out, a.threads),
                        os.path.join(fdir, "log.txt"))], 1)
    return out, res["final"]


def run_partition(a, work, spec, b, gframes, gpoints, rows):
    """Steps 2 to 4 for one partition K:H, its three rows added to `rows`."""
    k, halo = (int(x) for x in spec.split(":"))
    name = f"K{k}_H{halo}"
    subs = partition(b.lines, k, halo)
    res, phase_wall, split_s = adjust_sub_blocks(a, work, name, b, subs)
    t_merge = time.monotonic()
    est_frames, est_ties, est_checks, sub_iters = collect_estimates(subs)
    (owned, ties, checks), (averaged, ties_b, checks_b) = merge(subs, est_frames, est_ties, est_checks)
    missing = set(gpoints) - set(ties)
    merge_s = time.monotonic() - t_merge
    seam = seam_figures(est_frames, est_ties)
    largest = max(len(s["images"]) for s in subs)
    # The global adjustment's tie RMSE over the tie points the merge has (the others have
    # fewer than three rays in every sub-block, and are the weakest).
    seam["global_tie_rmse_same_points_mm"] = 1000 * rms(dist(gpoints[p], b.truth_points[p]) for p in ties)
    common = dict(split_s=split_s, merge_s=merge_s, images_per_process=largest, iterations="/".join(map(str, sub_iters)),
                  adjust_s=max(report(os.path.join(s["dir"], "out"))["summary"]["time_seconds"] for s in subs),
                  wall_s=phase_wall, peak_rss_mb=max(r["rss_mb"] for r in res.values()),
                  sum_cpu_s=sum(r["cpu_s"] for r in res.values()), **seam)
    add_row(rows, f"{name} merge A: owner's cameras, averaged points", k, halo,
            measure(owned, ties, checks, b.truth_frames, b.truth_points, b.surveyed), **common)
    add_row(rows, f"{name} merge B: averaged cameras, points from most rays", k, halo,
            measure(averaged, ties_b, checks_b, b.truth_frames, b.truth_points, b.surveyed))
    if missing:
        print(f"{name}: {len(missing)} tie points of the global adjustment are in no sub-block "
              "(seen by fewer than three images of every sub-block)")
    out, final = final_global(a, work, name, b, averaged, ties_b)
    frep = report(out)
    fframes = poses(os.path.join(out, "frames.csv"))
    to_cold = max(dist(c, gframes[img][0]) for img, (c, _) in fframes.items())
    add_row(rows, f"{name} merge B + final global", k, halo, measure_output(out, b),
            images_per_process=len(b.images), iterations=frep["summary"]["iterations"],
            adjust_s=frep["summary"]["time_seconds"], wall_s=final["wall_s"],
            peak_rss_mb=final["rss_mb"], initial_cost=frep["summary"]["initial_cost"],
            max_centre_offset_from_cold_mm=1000 * to_cold,
            report_check_rmse_mm=1000 * frep["check_rmse_m"]["total"])
    print(f"{name}: sub-blocks of {sorted(len(s['images']) for s in subs)} images done in "
          f"{phase_wall:.1f} s wall; final from the merge: {frep['summary']['iterations']} iterations, "
          f"{frep['summary']['time_seconds']:.2f} s", flush=True)


def write_table(a, work, rows):
    """The CSV of every figure and a Markdown table of the main ones on stdout."""
    fields = ["solution", "K", "halo_lines", "images_per_process", "camera_rmse_mm", "attitude_rms_arcsec",
              "check_rmse_mm", "tie_rmse_mm", "global_tie_rmse_same_points_mm", "seam_centre_rms_mm", "seam_centre_max_mm",
              "seam_attitude_rms_arcsec", "seam_tie_rms_mm", "seam_tie_max_mm", "overlap_images", "overlap_ties",
              "iterations", "initial_cost", "adjust_s", "wall_s", "sum_cpu_s", "peak_rss_mb", "split_s", "merge_s",
              "max_centre_offset_from_cold_mm", "report_check_rmse_mm"]
    path = a.csv or os.path.join(work, "partition_experiment.csv")
    fmt = lambda v: ("" if isinstance(v, float) and math.isnan(v) else f"{v:.4g}" if isinstance(v, float) else str(v))
    write_rows(path, fields, [{f: fmt(r.get(f, "")) for f in fields} for r in rows])
    shown = ["solution", "images_per_process", "camera_rmse_mm", "attitude_rms_arcsec", "check_rmse_mm",
             "tie_rmse_mm", "seam_centre_rms_mm", "seam_tie_rms_mm", "iterations", "adjust_s", "wall_s",
             "peak_rss_mb"]
    print()
    print("| " + " | ".join(shown) + " |")
    print("|" + "---|" * len(shown))
    for r in rows:
        print("| " + " | ".join(fmt(r.get(f, "")) for f in shown) + " |")
    print(f"\nwrote {path}")


def main():
    a = parse_args()
    work = a.work_dir
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    b = simulate_block(a, work)
    rows = []  # one per solution
    gframes, gpoints = run_global(a, work, b, rows)
    for spec in a.partitions.split(","):
        run_partition(a, work, spec, b, gframes, gpoints, rows)
    write_table(a, work, rows)


if __name__ == "__main__":
    main()
