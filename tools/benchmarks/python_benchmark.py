#!/usr/bin/env python3
"""The photopose Python module against the same calls in C++ (docs/performance.md, "Python
module"): what a call from Python costs on top of the library.

    PYTHONPATH=build/python python3 tools/benchmarks/python_benchmark.py \
        --peer=build/photopose_python_benchmark_peer [--images=10000] [--bundle_lines=5] \
        [--bundle_images_per_line=20] [--repeats=3] [--threads=0] [--work_dir=DIR] \
        [--only=resect|bundle]

1. Batch resection: --images synthetic images, 8 control points each (24 mm, 4 um pixels,
   6000 x 4000 px at 100 m, marks with 0.5 px noise and stated accuracy, a 30 px blunder in every
   tenth image), written as tables. Python reads them (read_block), builds the inputs
   (Block.resection_inputs) and times resect_images alone, without and with a progress callback
   (a Python function called from the resecting threads); the peer reads the same tables, builds
   the same inputs (MakeResectionInput) and times ResectImages alone, without and with a C++
   progress hook that counts its calls.
2. Bundle: a synthetic block of --bundle_lines x --bundle_images_per_line images written as
   tables; both read them and time the bundle adjustment alone (default options, then without the
   per-observation diagnostics), each run on a fresh copy of the block. The sides alternate call
   by call (Python first on even repeats, C++ first on odd ones: the peer runs one call per
   launch), so that a change of the machine's load between calls falls on both; neither side
   times the freeing of the previous call's result.
Each side runs each call --repeats times; the table gives the median and the fastest run of each
side and their ratios (the machine is shared: the fastest run is the least disturbed). Both sides'
poses must agree (printed), so that the same work is timed.
"""

import argparse
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import photopose as pp


def resection_tables(directory, num_images, seed=1):
    rng = np.random.default_rng(seed)
    camera = pp.FrameCamera(camera_id="bench", focal_length_um=24000.0, pixel_size_um=4.0,
                            n_columns=6000, n_rows=4000)
    per_image = 8
    side = int(np.ceil(np.sqrt(num_images)))
    ids, xyz, rasters, mark_ids, marks = [], [], [], [], []
    for i in range(num_images):
        center = np.array([500000.0 + 60.0 * (i % side), 4100000.0 + 60.0 * (i // side), 110.0])
        # Lines flown north and south (kappa 0 or 180 deg), a few degrees of attitude noise.
        angles = np.radians(rng.uniform(-3.0, 3.0, 3)) + [0.0, 0.0, np.pi * (i // side % 2)]
        eo = pp.ExteriorOrientation(center, angles)
        points = np.c_[center[:2] + rng.uniform([-35.0, -22.0], [35.0, 22.0], (per_image, 2)),
                       rng.uniform(0.0, 10.0, per_image)]
        pixels = camera.project(eo, points) + rng.normal(0.0, 0.5, (per_image, 2))
        if i % 10 == 0:
            pixels[0] += 30.0
        names = [f"G{i}_{k}" for k in range(per_image)]
        ids += names
        xyz.append(points)
        rasters += [f"img_{i:05d}"] * per_image
        mark_ids += names
        marks.append(pixels)
    block = pp.Block.from_arrays([camera], ids, np.vstack(xyz), rasters, mark_ids, np.vstack(marks),
                                 mark_accuracy=0.5)
    pp.write_block_tables(block, cameras=directory / "cameras.csv", points=directory / "points.csv",
                          marks=directory / "marks.csv")


def bundle_tables(directory, lines, images_per_line):
    block, _ = pp.simulate_block(seed=1, num_lines=lines, images_per_line=images_per_line)
    pp.write_block_tables(block, cameras=directory / "cameras.csv", points=directory / "points.csv",
                          marks=directory / "marks.csv", frames=directory / "frames.csv")


def run_peer(peer, mode, directory, threads, repeats):
    out = directory / f"cpp_{mode}_poses.txt"
    done = subprocess.run([str(peer), mode, str(directory), str(threads), str(repeats), str(out)],
                          capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"peer failed: {done.stderr}")
    seconds = [float(s) for s in done.stdout.split("seconds:")[1].split()]
    poses = np.loadtxt(out, ndmin=2)[:, 1:]
    calls = done.stdout.split("progress calls:")[1].split()[0] if "progress calls:" in done.stdout else None
    return seconds, poses, calls


def pose_difference(a, b):
    both = ~np.isnan(a).any(axis=1) & ~np.isnan(b).any(axis=1)
    if not np.array_equal(np.isnan(a).any(axis=1), np.isnan(b).any(axis=1)):
        return float("inf")
    return float(np.abs(a[both] - b[both]).max()) if both.any() else 0.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--peer", required=True, help="build/photopose_python_benchmark_peer")
    parser.add_argument("--images", type=int, default=10000)
    parser.add_argument("--bundle_lines", type=int, default=5)
    parser.add_argument("--bundle_images_per_line", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=0, help="0: all cores (both sides)")
    parser.add_argument("--work_dir", default=None, help="default: a temporary folder")
    parser.add_argument("--only", choices=("resect", "bundle"), default=None,
                        help="time these calls alone (default: both)")
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as scratch:
        work = pathlib.Path(args.work_dir or scratch)
        rows = []

        if args.only != "bundle":
            rows += resection_rows(args, work)
        if args.only != "resect":
            rows += bundle_rows(args, work)

    print(f"{args.repeats} runs a side; median (fastest) in seconds")
    print("| call | Python (s) | C++ (s) | Python / C++ | largest pose difference |")
    print("|---|---|---|---|---|")
    for name, python_s, cpp_s, difference in rows:
        python_m, cpp_m = float(np.median(python_s)), float(np.median(cpp_s))
        print(f"| {name} | {python_m:.3f} ({min(python_s):.3f}) | {cpp_m:.3f} ({min(cpp_s):.3f}) | "
              f"{python_m / cpp_m:.3f} ({min(python_s) / min(cpp_s):.3f}) | {difference:.1e} |")


def resection_rows(args, work):
    rows = []
    resect_dir = work / "resect"
    resect_dir.mkdir(parents=True, exist_ok=True)
    resection_tables(resect_dir, args.images)
    block = pp.read_block(resect_dir / "cameras.csv", resect_dir / "points.csv",
                          resect_dir / "marks.csv")
    images, inputs = block.resection_inputs()
    for with_progress in (False, True):
        mode = "resect_progress" if with_progress else "resect"
        cpp_seconds, cpp_poses, cpp_calls = run_peer(args.peer, mode, resect_dir, args.threads,
                                                     args.repeats)
        infos = []
        progress = infos.append if with_progress else None
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            results = pp.resect_images(inputs, num_threads=args.threads, progress=progress)
            times.append(time.perf_counter() - start)
        python_poses = np.full((block.num_images, 6), np.nan)
        for image, result in zip(images, results):
            if result.success:
                python_poses[image] = result.eo.parameters
        solved = int((~np.isnan(python_poses).any(axis=1)).sum())
        name = f"resect_images, {len(inputs)} images ({solved} solved)"
        if with_progress:
            name += (f", progress (Python: {len(infos) // args.repeats} calls; "
                     f"C++: a hook, {cpp_calls} calls)")
        rows.append((name, times, cpp_seconds, pose_difference(python_poses, cpp_poses)))
    return rows


def bundle_rows(args, work):
    rows = []
    bundle_dir = work / "bundle"
    bundle_dir.mkdir(parents=True, exist_ok=True)
    bundle_tables(bundle_dir, args.bundle_lines, args.bundle_images_per_line)
    block = pp.read_block(bundle_dir / "cameras.csv", bundle_dir / "points.csv",
                          bundle_dir / "marks.csv", frames=bundle_dir / "frames.csv")
    for diagnostics, mode in ((True, "bundle"), (False, "bundle_no_diagnostics")):
        options = pp.BundleAdjustmentOptions()
        options.solver.num_threads = args.threads
        options.statistics.observation_diagnostics = diagnostics
        times, cpp_seconds = [], []
        for repeat in range(args.repeats):
            if repeat % 2 == 1:
                cpp_seconds += run_peer(args.peer, mode, bundle_dir, args.threads, 1)[0]
            adjusted = block.copy()
            result = None  # the previous result freed here, outside the timing (as in C++)
            start = time.perf_counter()
            result = pp.bundle_adjust(adjusted, options)
            times.append(time.perf_counter() - start)
            if not result.summary.is_solution_usable():
                sys.exit(f"bundle: {result.summary.message}")
            if repeat % 2 == 0:
                seconds, cpp_poses, _ = run_peer(args.peer, mode, bundle_dir, args.threads, 1)
                cpp_seconds += seconds
        name = f"bundle_adjust, {block.num_images} images, {block.num_marks} marks"
        if not diagnostics:
            name += ", observation_diagnostics off"
        rows.append((name, times, cpp_seconds, pose_difference(adjusted.image_parameters, cpp_poses)))
    return rows


if __name__ == "__main__":
    main()
