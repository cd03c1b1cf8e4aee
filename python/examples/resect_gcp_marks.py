"""Resect every image from ground control marks held in numpy arrays.

    python3 resect_gcp_marks.py GCP_LIST_TXT

The marks come from an OpenDroneMap gcp_list.txt (one line per mark: X Y Z column row image
[name], pixels with (0, 0) at the image's top-left corner, Row down), read here with numpy as a
pipeline would hold them; the camera is the flight's (4000 x 3000 px, 1.55 um pixels, f = 4.5 mm).
"""

import sys

import numpy as np

import photopose as pp

path = sys.argv[1]
with open(path) as f:
    crs = f.readline().strip()
    rows = [line.split() for line in f if line.strip()]
xyz = np.array([r[0:3] for r in rows], dtype=float)         # N x 3 ground (m, the CRS above)
column_row = np.array([r[3:5] for r in rows], dtype=float)  # N x 2 pixel marks
rasters = [r[5] for r in rows]
names = [r[6] if len(r) > 6 else f"{r[0]}_{r[1]}_{r[2]}" for r in rows]

camera = pp.FrameCamera(camera_id="SX260HS", focal_length_um=4500.0,
                        pixel_size_um=1.5495867768595042, n_columns=4000, n_rows=3000)
# One ground point per name (the same target is marked in several images).
point_ids, first = np.unique(names, return_index=True)
block = pp.Block.from_arrays([camera], list(point_ids), xyz[first], rasters, names, column_row,
                             mark_accuracy=2.0, crs=crs)            # marks: 2 px, one sigma
images, inputs = block.resection_inputs()
results = pp.resect_images(inputs)                                  # all cores, GIL released

print(f"{block!r}")
solved = 0
for image, result in zip(images, results):
    name = block.image_names[image]
    if not result.success:
        print(f"{name}: not solved: {result.summary.message}")
        continue
    solved += 1
    x, y, z = result.eo.center_in_ground
    omega, phi, kappa = result.eo.angles_deg("opk")                 # PATB / Wolf & Dewitt angles
    sx, sy, sz = result.standard_deviations[:3]
    print(f"{name}: X={x:.3f} Y={y:.3f} Z={z:.3f} m (+-{sx:.3f} {sy:.3f} {sz:.3f}) "
          f"opk=({omega:.4f}, {phi:.4f}, {kappa:.4f}) deg sigma0={result.sigma0:.2f} "
          f"marks={result.num_inliers}/{len(result.inliers)}")
print(f"{solved} of {len(results)} images solved")
