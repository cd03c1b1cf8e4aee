#!/usr/bin/env python3
"""The photopose Python module against the same calls in C++ (docs/performance.md, "Python
module"): what a call from Python costs on top of the library, measured so that a shared, loaded
machine does not decide the answer.

    PYTHONPATH=build/python python3 tools/benchmarks/python_benchmark.py \
        --peer=build/photopose_python_benchmark_peer [--images=10000] [--bundle_lines=5] \
        [--bundle_images_per_line=20] [--pairs=20] [--warmup=1] [--threads=0,1] \
        [--work_dir=DIR] [--only=resect|bundle] [--raw=FILE.csv]

The calls (the same tables read by both sides):
1. Batch resection: --images synthetic images, 8 control points each (24 mm, 4 um pixels,
   6000 x 4000 px at 100 m, marks with 0.5 px noise and stated accuracy, a 30 px blunder in every
   tenth image). Python reads them (read_block), builds the inputs once (Block.resection_inputs)
   and measures resect_images alone, without and with a progress callback (a Python function
   called from the resecting threads); the peer builds the same inputs once (MakeResectionInput)
   and measures ResectImages alone, without and with a C++ hook that counts its calls.
2. Bundle: a synthetic block of --bundle_lines x --bundle_images_per_line images; both sides
   measure the bundle adjustment alone (default options, then without the per-observation
   diagnostics), each call on a fresh copy of the block made before the measurement; neither side
   measures the freeing of the previous call's result.

How: the peer (photopose_python_benchmark_peer) stays up for a whole row and makes one call each
time the script asks, so the two sides' calls alternate: pair i is Python then C++ for even i, C++
then Python for odd i, after --warmup pairs that are not counted. Each call gives its wall time and
the CPU time of its process during the call (getrusage RUSAGE_SELF, user + system of every thread,
on both sides): CPU time counts the work done and, unlike wall time, not the time a thread waits
for a core another program holds. Every pair gives a ratio Python / C++ of each; a row gives the
median of its pairs' ratios with a distribution-free confidence interval (order statistics of the
median: at least 95 % coverage, the exact coverage printed), and the verdict against the target
(met: the interval's upper end within it; not met: its lower end beyond it; else undecided).
Each row runs for every thread count of --threads (0: all cores, both sides; 1 is the control
without thread scheduling). Both sides' poses are compared after every pair (largest absolute
difference, m and rad; NaN patterns must match), and each side's against its own first call.
Hardware counters (instructions, cycles) would count the work without the machine's load; the peer
reports whether perf_event_open gives them here (a VM without a virtual PMU does not). Then
--instructions counts them in software: one call a side under callgrind (valgrind, one thread: it
runs a process's threads one at a time), the inclusive instructions of the library function
(ResectImages, BundleAdjust) on both sides and of the module's bound call (pybind11's dispatcher:
arguments converted, the GIL released, the library call, the result converted) in Python. These
counts do not change with the load; they say how much more work a call from Python does, not how
long an instruction takes.
"""

import argparse
import csv
import math
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

import photopose as pp

# The targets of issue 24: Python / C++ at most 1 + these.
RESECT_TARGET = 0.10
BUNDLE_TARGET = 0.05
# The confidence interval's least coverage (two-sided).
CONFIDENCE = 0.95


# ------------------------------------------------------------------ statistics of the pairs

def median_interval(values, confidence=CONFIDENCE):
    """The median of `values` and a distribution-free confidence interval for the population median
    from order statistics: [x_(k), x_(n+1-k)] (1-based, sorted) with the largest k whose coverage
    1 - 2 P(B <= k - 1), B ~ Binomial(n, 1/2), is at least `confidence`. Returns (median, low, high,
    coverage); with too few values for that coverage the interval is the whole range and the
    coverage is that of k = 1 (1 - 2^(1 - n))."""
    x = sorted(values)
    n = len(x)
    if n == 0:
        raise ValueError("median_interval: no values")
    k = 1
    while k + 1 <= (n + 1) // 2 and 1.0 - 2.0 * binomial_half_cdf(k, n) >= confidence:
        k += 1
    coverage = 1.0 - 2.0 * binomial_half_cdf(k - 1, n)
    return float(np.median(x)), x[k - 1], x[n - k], coverage


def binomial_half_cdf(j, n):
    """P(B <= j) for B ~ Binomial(n, 1/2)."""
    return sum(math.comb(n, i) for i in range(j + 1)) / 2.0 ** n


def verdict(low, high, target):
    """Whether a ratio's interval [low, high] is within 1 + target: 'met', 'not met' or 'undecided'."""
    if high <= 1.0 + target:
        return "met"
    if low > 1.0 + target:
        return "not met"
    return "undecided"


def pose_difference(a, b):
    """Largest absolute difference of two N x 6 pose arrays (m, rad); inf when their NaN rows
    (unsolved images) differ."""
    unsolved_a, unsolved_b = np.isnan(a).any(axis=1), np.isnan(b).any(axis=1)
    if a.shape != b.shape or not np.array_equal(unsolved_a, unsolved_b):
        return float("inf")
    both = ~unsolved_a
    return float(np.abs(a[both] - b[both]).max()) if both.any() else 0.0


# ------------------------------------------------------------------ the tables

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


# ------------------------------------------------------------------ the two sides

def cpu_seconds():
    """CPU time of this process so far, every thread's user + system time (s), as the peer reads
    its own."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


class Peer:
    """The C++ side of one row: one peer process that makes a call whenever asked."""

    def __init__(self, path, mode, directory, threads):
        self.poses_path = directory / f"cpp_{mode}_poses.txt"
        self.process = subprocess.Popen([str(path), mode, str(directory), str(threads),
                                         str(self.poses_path)], stdin=subprocess.PIPE,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.hardware_counters = None
        while True:
            line = self._line()
            if line.startswith("hardware counters:"):
                self.hardware_counters = line.split(":", 1)[1].strip()
            if line == "ready":
                break

    def _line(self):
        line = self.process.stdout.readline()
        if not line:
            self.process.kill()
            sys.exit(f"peer failed: {self.process.stderr.read().strip()}")
        return line.strip()

    def call(self):
        """One call: (wall s, CPU s, progress calls, poses N x 6)."""
        self.process.stdin.write("call\n")
        self.process.stdin.flush()
        line = self._line()
        if not line.startswith("call:"):
            sys.exit(f"peer: unexpected line '{line}'")
        wall, cpu, progress_calls = line.split()[1:]
        poses = np.loadtxt(self.poses_path, ndmin=2)[:, 1:]
        return float(wall), float(cpu), int(progress_calls), poses

    def close(self):
        self.process.stdin.close()
        if self.process.wait() != 0:
            sys.exit(f"peer failed: {self.process.stderr.read().strip()}")


class PythonResection:
    def __init__(self, block, threads, with_progress):
        self.images, self.inputs = block.resection_inputs()
        self.num_images = block.num_images
        self.threads = threads
        self.with_progress = with_progress
        self.infos = []
        self.results = None

    def prepare(self):
        self.results = None  # the previous results freed here, outside the measurement
        self.infos = []

    def call(self):
        progress = self.infos.append if self.with_progress else None
        self.results = pp.resect_images(self.inputs, num_threads=self.threads, progress=progress)

    def poses(self):
        poses = np.full((self.num_images, 6), np.nan)
        for image, result in zip(self.images, self.results):
            if result.success:
                poses[image] = result.eo.parameters
        return poses

    def progress_calls(self):
        return len(self.infos)


class PythonBundle:
    def __init__(self, block, threads, diagnostics):
        self.block = block
        self.options = pp.BundleAdjustmentOptions()
        self.options.solver.num_threads = threads
        self.options.statistics.observation_diagnostics = diagnostics
        self.adjusted = None
        self.result = None

    def prepare(self):
        self.adjusted = self.block.copy()
        self.result = None  # the previous result freed here, outside the measurement (as in C++)

    def call(self):
        self.result = pp.bundle_adjust(self.adjusted, self.options)

    def poses(self):
        if not self.result.summary.is_solution_usable():
            sys.exit(f"bundle: {self.result.summary.message}")
        return self.adjusted.image_parameters

    def progress_calls(self):
        return 0


def python_call(side):
    """One call of the Python side: (wall s, CPU s, progress calls, poses N x 6)."""
    side.prepare()
    cpu_start = cpu_seconds()
    start = time.perf_counter()
    side.call()
    wall = time.perf_counter() - start
    cpu = cpu_seconds() - cpu_start
    return wall, cpu, side.progress_calls(), side.poses()


def load_average():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def measure_row(args, name, target, side, mode, directory, threads, raw_rows):
    """Alternating pairs of calls of one row; returns its figures."""
    peer = Peer(args.peer, mode, directory, threads)
    python, cpp, loads = [], [], []
    difference = 0.0                     # Python against C++, same pair
    python_spread = cpp_spread = 0.0     # each side against its own first counted call
    progress = set()
    for pair in range(args.warmup + args.pairs):
        loads.append(load_average())
        if pair % 2 == 0:
            p = python_call(side)
            c = peer.call()
        else:
            c = peer.call()
            p = python_call(side)
        if pair < args.warmup:
            continue
        python.append(p)
        cpp.append(c)
        progress.add((p[2], c[2]))
        difference = max(difference, pose_difference(p[3], c[3]))
        python_spread = max(python_spread, pose_difference(p[3], python[0][3]))
        cpp_spread = max(cpp_spread, pose_difference(c[3], cpp[0][3]))
        raw_rows.append((name, threads, pair - args.warmup, "python first" if pair % 2 == 0 else
                         "C++ first", p[0], c[0], p[1], c[1], loads[-1]))
    peer.close()
    loads.append(load_average())
    row = {"name": name, "threads": threads, "target": target, "difference": difference,
           "python_spread": python_spread, "cpp_spread": cpp_spread, "progress": sorted(progress),
           "load": (min(loads), max(loads)), "hardware_counters": peer.hardware_counters}
    for k, measure in ((0, "wall"), (1, "cpu")):
        row[f"python_{measure}"] = float(np.median([p[k] for p in python]))
        row[f"cpp_{measure}"] = float(np.median([c[k] for c in cpp]))
        row[f"{measure}_ratio"] = median_interval([p[k] / c[k] for p, c in zip(python, cpp)])
    return row


def tables_folder(args, work, kind):
    """work/resect or work/bundle with its tables, made unless there."""
    directory = work / kind
    directory.mkdir(parents=True, exist_ok=True)
    if not (directory / "marks.csv").exists():
        if kind == "resect":
            resection_tables(directory, args.images)
        else:
            bundle_tables(directory, args.bundle_lines, args.bundle_images_per_line)
    return directory


def row_name(block, mode, side):
    if mode.startswith("resect"):
        name = f"resect_images, {len(side.inputs)} images"
    else:
        name = f"bundle_adjust, {block.num_images} images, {block.num_marks} marks"
    return name + {"resect_progress": ", progress (Python: a callback; C++: a hook)",
                   "bundle_no_diagnostics": ", observation_diagnostics off"}.get(mode, "")


def timed_rows(args, work, kind, threads, raw_rows):
    """The rows of one kind of call ('resect' or 'bundle') on `threads` threads."""
    directory = tables_folder(args, work, kind)
    block = read_tables(directory, kind)
    target = RESECT_TARGET if kind == "resect" else BUNDLE_TARGET
    modes = ("resect", "resect_progress") if kind == "resect" else ("bundle", "bundle_no_diagnostics")
    rows = []
    for mode in modes:
        side = python_side(block, mode, threads)
        rows.append(measure_row(args, row_name(block, mode, side), target, side, mode, directory,
                                threads, raw_rows))
    return rows


# ------------------------------------------------------------------ instructions (callgrind)

# The function whose inclusive instructions are the library's work, per mode: (name start, a part
# of its signature that tells it from an overload).
LIBRARY_FUNCTION = {
    "resect": ("photopose::ResectImages(", "ResectionBatchOptions const&"),
    "bundle": ("photopose::BundleAdjust(", "BundleAdjustmentOptions const&"),
}
# The module's entry of the call (pybind11's dispatcher of the bound function: argument
# conversion, the GIL released, the library call, the result converted), per mode.
BINDING_FUNCTION = {
    "resect": ("pybind11::cpp_function::initialize<photopose::python::",
               "{lambda(std::vector<photopose::ResectionInput"),
    "bundle": ("pybind11::cpp_function::initialize<photopose::python::", "BindBundleAdjust"),
}


def python_side(block, mode, threads):
    if mode.startswith("resect"):
        return PythonResection(block, threads, mode == "resect_progress")
    return PythonBundle(block, threads, mode == "bundle")


def read_tables(directory, mode):
    frames = {"frames": directory / "frames.csv"} if mode.startswith("bundle") else {}
    return pp.read_block(directory / "cameras.csv", directory / "points.csv",
                         directory / "marks.csv", **frames)


def child(args):
    """--child=MODE: one call of the Python side on the tables in --work_dir, as callgrind runs it."""
    kind = "resect" if args.child.startswith("resect") else "bundle"
    directory = pathlib.Path(args.work_dir) / kind
    side = python_side(read_tables(directory, args.child), args.child, int(args.threads))
    python_call(side)


def inclusive_instructions(callgrind_out, name_start, signature_part):
    """The largest inclusive instruction count (Ir) of a function whose name starts with
    name_start and contains signature_part, from callgrind_annotate's listing of a callgrind output
    file (its lines: "COUNT (PERCENT)  FILE:FUNCTION [OBJECT]")."""
    listing = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                              str(callgrind_out)], capture_output=True, text=True, check=True).stdout
    best = None
    for line in listing.splitlines():
        fields = line.split(None, 2)
        if len(fields) < 3 or not fields[0].replace(",", "").isdigit():
            continue
        at = fields[2].find(":" + name_start)
        if at >= 0 and signature_part in fields[2][at:]:
            count = int(fields[0].replace(",", ""))
            best = count if best is None else max(best, count)
    if best is None:
        sys.exit(f"{callgrind_out}: no function {name_start}...{signature_part}... "
                 "in callgrind's listing")
    return best


def instruction_rows(args, work):
    """Instructions of one call a side under callgrind, one thread (valgrind runs a process's
    threads one at a time): the library's work on each side and the whole bound call in Python."""
    env = dict(os.environ)
    rows = []
    modes = [m for m in ("resect", "bundle", "bundle_no_diagnostics")
             if args.only is None or m.startswith(args.only)]
    for mode in modes:
        kind = "resect" if mode.startswith("resect") else "bundle"
        directory = tables_folder(args, work, kind)
        python_out = directory / f"callgrind_python_{mode}.out"
        cpp_out = directory / f"callgrind_cpp_{mode}.out"
        valgrind = [args.valgrind, "--tool=callgrind", "--quiet"]
        subprocess.run(valgrind + [f"--callgrind-out-file={python_out}", sys.executable,
                                   os.path.abspath(__file__), "--peer", str(args.peer), "--child", mode,
                                   "--work_dir", str(work), "--threads", "1"], env=env, check=True)
        subprocess.run(valgrind + [f"--callgrind-out-file={cpp_out}", str(args.peer), mode,
                                   str(directory), "1", str(directory / "callgrind_poses.txt")],
                       input="call\n", text=True, check=True, capture_output=True)
        library = LIBRARY_FUNCTION[kind]
        rows.append({"name": mode, "python_library": inclusive_instructions(python_out, *library),
                     "python_call": inclusive_instructions(python_out, *BINDING_FUNCTION[kind]),
                     "cpp_library": inclusive_instructions(cpp_out, *library)})
    return rows


def print_instruction_rows(rows):
    print("instructions of one call a side (callgrind, 1 thread): the library function on each side, "
          "and Python's whole bound call (pybind11's dispatcher)")
    print("| call | C++: library | Python: library | Python: bound call | library Python / C++ "
          "| bound call / C++ library |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['name']} | {r['cpp_library']:,} | {r['python_library']:,} | {r['python_call']:,} "
              f"| {r['python_library'] / r['cpp_library']:.5f} "
              f"| {r['python_call'] / r['cpp_library']:.5f} |")


def print_rows(args, rows):
    coverage = rows[0]["wall_ratio"][3]
    print(f"{args.pairs} alternating pairs a row after {args.warmup} not counted; medians of each "
          f"side (s) and of the pairs' ratios Python / C++ [order-statistic interval, coverage "
          f"{100 * coverage:.1f} %]; verdict on the CPU-time interval")
    print(f"hardware counters: {rows[0]['hardware_counters']}")
    print("| call | threads | wall Python / C++ (s) | wall ratio | CPU Python / C++ (s) | CPU ratio "
          "| target | verdict (CPU) | verdict (wall) | poses: Python - C++; within a side | "
          "progress calls | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        wall, cpu = r["wall_ratio"], r["cpu_ratio"]
        progress = ", ".join(f"{p}/{c}" for p, c in r["progress"])
        print(f"| {r['name']} | {r['threads'] or 'all'} | {r['python_wall']:.3f} / {r['cpp_wall']:.3f} "
              f"| {wall[0]:.3f} [{wall[1]:.3f}, {wall[2]:.3f}] "
              f"| {r['python_cpu']:.3f} / {r['cpp_cpu']:.3f} "
              f"| {cpu[0]:.3f} [{cpu[1]:.3f}, {cpu[2]:.3f}] | {1 + r['target']:.2f} "
              f"| {verdict(cpu[1], cpu[2], r['target'])} | {verdict(wall[1], wall[2], r['target'])} "
              f"| {r['difference']:.1e}; {r['python_spread']:.1e} / {r['cpp_spread']:.1e} "
              f"| {progress} | {r['load'][0]:.1f}-{r['load'][1]:.1f} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--peer", required=True, help="build/photopose_python_benchmark_peer")
    parser.add_argument("--images", type=int, default=10000, help="images of the batch resection")
    parser.add_argument("--bundle_lines", type=int, default=5, help="flight lines of the bundle's block")
    parser.add_argument("--bundle_images_per_line", type=int, default=20,
                        help="images per line of the bundle's block")
    parser.add_argument("--pairs", type=int, default=20,
                        help="counted pairs of calls per row (0: no timed rows, --instructions alone)")
    parser.add_argument("--warmup", type=int, default=1, help="pairs before them, not counted")
    parser.add_argument("--threads", default="0,1",
                        help="comma-separated thread counts, each a set of rows (0: all cores)")
    parser.add_argument("--work_dir", default=None,
                        help="the tables' folder, tables already there reused (default: a temporary one)")
    parser.add_argument("--only", choices=("resect", "bundle"), default=None,
                        help="measure these calls alone (default: both)")
    parser.add_argument("--raw", default=None, help="write every counted call's figures to this CSV")
    parser.add_argument("--instructions", action="store_true",
                        help="also count each side's instructions of one call under callgrind (slow)")
    parser.add_argument("--valgrind", default="valgrind", help="the valgrind executable")
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args)
        return
    if args.pairs < 0 or args.warmup < 0 or (args.pairs == 0 and not args.instructions):
        parser.error("--pairs must be >= 1 (or 0 with --instructions) and --warmup >= 0")
    try:
        thread_counts = [int(t) for t in args.threads.split(",")]
    except ValueError:
        parser.error(f"--threads: expected comma-separated integers, got '{args.threads}'")
    if any(t < 0 for t in thread_counts):
        parser.error("--threads: each count must be >= 0")

    raw_rows = []
    with tempfile.TemporaryDirectory() as scratch:
        work = pathlib.Path(args.work_dir or scratch)
        rows = []
        for threads in thread_counts if args.pairs > 0 else []:
            for kind in ("resect", "bundle"):
                if args.only in (None, kind):
                    rows += timed_rows(args, work, kind, threads, raw_rows)
        instructions = instruction_rows(args, work) if args.instructions else []
    if rows:
        print_rows(args, rows)
    if instructions:
        print_instruction_rows(instructions)
    if args.raw:
        with open(args.raw, "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(("call", "threads", "pair", "order", "python_wall_s", "cpp_wall_s",
                             "python_cpu_s", "cpp_cpu_s", "load_1min"))
            writer.writerows(raw_rows)


if __name__ == "__main__":
    main()
