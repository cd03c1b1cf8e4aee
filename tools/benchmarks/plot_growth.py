#!/usr/bin/env python3
"""The growth plot of docs/performance.md from `bundle_scaling.sh growth` runs (standard library).

    python3 tools/benchmarks/plot_growth.py build/bundle_scaling docs/bundle_growth.svg

Reads WORK/growth<N>.{json,time,log}: marks, peak resident memory (/usr/bin/time), seconds per
iteration (photopose's progress lines, iteration 1 on), and writes an SVG with both on log-log
axes against the number of marks, each with its power-law fit, and prints the fits.
"""
import glob
import json
import math
import os
import re
import sys


def measure(work):
    rows = []
    for path in glob.glob(os.path.join(work, "growth*.json")):
        label = os.path.basename(path)[:-5]
        summary = json.load(open(path))["summary"]
        text = open(os.path.join(work, label + ".time")).read()
        peak_mib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) / 1024
        log = open(os.path.join(work, label + ".log")).read()
        steps = [float(b) for it, b in re.findall(r"iteration +(\d+):.* of ([\d.]+) s", log) if int(it) > 0]
        rows.append((summary["num_images"], summary["num_marks"], sum(steps) / len(steps), peak_mib))
    return sorted(rows)


def fit(xs, ys):
    """Least-squares y = a x^b on log axes: (a, b)."""
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    b = sum((u - mx) * (v - my) for u, v in zip(lx, ly)) / sum((u - mx) ** 2 for u in lx)
    return math.exp(my - b * mx), b


def svg(rows, out):
    width, height, left, right, top, bottom = 640, 400, 70, 70, 30, 50
    marks = [r[1] for r in rows]
    x0, x1 = math.log10(min(marks) / 1.5), math.log10(max(marks) * 1.5)
    series = [("s per iteration", [r[2] for r in rows], "#1f77b4", "left"),
              ("peak memory (MiB)", [r[3] for r in rows], "#d62728", "right")]
    def px(x):
        return left + (math.log10(x) - x0) / (x1 - x0) * (width - left - right)
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             f'font-family="sans-serif" font-size="12">',
             f'<rect width="{width}" height="{height}" fill="white"/>',
             f'<text x="{width / 2}" y="18" text-anchor="middle">photopose bundle: growth with the '
             f'block (log-log; {", ".join(str(r[0]) for r in rows)} images)</text>']
    for name, ys, colour, side in series:
        y0, y1 = math.log10(min(ys) / 1.5), math.log10(max(ys) * 1.5)
        def py(y):
            return height - bottom - (math.log10(y) - y0) / (y1 - y0) * (height - top - bottom)
        a, b = fit(marks, ys)
        xs = [min(marks) / 1.2, max(marks) * 1.2]
        parts.append(f'<line x1="{px(xs[0]):.1f}" y1="{py(a * xs[0] ** b):.1f}" x2="{px(xs[1]):.1f}" '
                     f'y2="{py(a * xs[1] ** b):.1f}" stroke="{colour}" stroke-dasharray="4 3"/>')
        parts.append('<polyline fill="none" stroke="%s" stroke-width="2" points="%s"/>' % (
            colour, " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in zip(marks, ys))))
        for x, y in zip(marks, ys):
            parts.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="4" fill="{colour}"/>')
            parts.append(f'<text x="{px(x) + 6:.1f}" y="{py(y) - 6:.1f}" fill="{colour}">{y:.3g}</text>')
        axis_x = left if side == "left" else width - right
        parts.append(f'<line x1="{axis_x}" y1="{top}" x2="{axis_x}" y2="{height - bottom}" stroke="{colour}"/>')
        label_x = 16 if side == "left" else width - 16
        parts.append(f'<text x="{label_x}" y="{height / 2}" fill="{colour}" text-anchor="middle" '
                     f'transform="rotate(-90 {label_x} {height / 2})">{name}, fit ∝ marks^{b:.2f}</text>')
        print(f"{name}: {a:.4g} * marks^{b:.3f}")
    parts.append(f'<line x1="{left}" y1="{height - bottom}" x2="{width - right}" y2="{height - bottom}" stroke="black"/>')
    for x in marks:
        parts.append(f'<text x="{px(x):.1f}" y="{height - bottom + 16}" text-anchor="middle">{x / 1e6:.2g} M</text>')
    parts.append(f'<text x="{width / 2}" y="{height - 12}" text-anchor="middle">marks (image observations)</text>')
    parts.append("</svg>")
    with open(out + ".tmp", "w") as f:
        f.write("\n".join(parts) + "\n")
    os.replace(out + ".tmp", out)


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_growth.py WORK OUT.svg")
    rows = measure(sys.argv[1])
    if len(rows) < 2:
        sys.exit("plot_growth.py: fewer than two growth runs in " + sys.argv[1])
    for r in rows:
        print(f"{r[0]} images, {r[1]} marks: {r[2]:.3f} s per iteration, peak {r[3]:.0f} MiB")
    svg(rows, sys.argv[2])
    print("plot_growth.py: wrote " + sys.argv[2])


if __name__ == "__main__":
    main()
