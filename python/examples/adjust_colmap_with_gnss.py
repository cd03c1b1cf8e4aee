"""Adjust a COLMAP model with GNSS camera positions from a frames table as priors.

    python3 adjust_colmap_with_gnss.py COLMAP_DIR GNSS_FRAMES_CSV OUT_DIR

COLMAP's model lives in its own arbitrary frame; the GNSS positions (PerspectiveX/Y/Z with
AccuracyX/Y/Z, metres, a projected CRS) in the ground frame. The model is first moved onto the
positions by a similarity fitted here in numpy (Umeyama); the bundle adjustment then weighs tie
marks against the positions (priors) and reports whether the block bends to them. The library's
georeferencing call with CRSs will replace the numpy similarity.
"""

import sys

import numpy as np

import photopose as pp

model_dir, frames_csv, out_dir = sys.argv[1:4]
block = pp.read_colmap_model(model_dir)
gnss = {f.raster: f for f in pp.read_frames_table(frames_csv)}

# GNSS centre and accuracy per image of the model (NaN rows: no position).
n = block.num_images
centers = np.full((n, 3), np.nan)
accuracy = np.full((n, 3), np.nan)
for i, name in enumerate(block.image_names):
    if name in gnss:
        centers[i] = gnss[name].eo.center_in_ground
        if gnss[name].center_accuracy_m is not None:
            accuracy[i] = gnss[name].center_accuracy_m

# Similarity ground = s R model + t from the camera centres (Umeyama 1991).
have = ~np.isnan(centers).any(axis=1)
model_centers = block.image_centers[have]
mu_m, mu_g = model_centers.mean(axis=0), centers[have].mean(axis=0)
a, b = model_centers - mu_m, centers[have] - mu_g
u, d, vt = np.linalg.svd(b.T @ a / len(a))
flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
R = u @ flip @ vt
s = np.trace(np.diag(d) @ flip) / (a ** 2).sum(axis=1).mean()
t = mu_g - s * R @ mu_m

# Move the block: centres and points by the similarity, R_camera_from_ground by R^T.
poses = block.image_parameters
for i in range(n):
    eo = pp.ExteriorOrientation.from_matrix(pp.rotation_from_angles(poses[i, 3:]) @ R.T,
                                            s * R @ poses[i, :3] + t)
    poses[i] = eo.parameters
block.set_image_parameters(poses)
block.set_point_positions(s * block.point_positions @ R.T + t)
block.set_measured_centers(centers, accuracy_m=accuracy)

options = pp.BundleAdjustmentOptions()
options.accuracies.tie_px = 1.0                        # px, one sigma
options.accuracies.camera_m = [0.05, 0.05, 0.10]       # rows without AccuracyX/Y/Z (m)
result = pp.bundle_adjust(block, options, progress=lambda info: print(
    f"  round {info.round} iteration {info.iteration}: sigma0 {info.sigma0:.3f}"))
print(result.summary.brief_report())
for group in result.groups:
    verdict = "OVERFIT: " + group.message if group.overfit else "ok"
    print(f"{group.group}: n={group.count} rms={group.rms_total:.4f} {group.unit} "
          f"ratio={group.ratio:.2f} redundancy share={group.redundancy_share:.2f} {verdict}")
if not result.summary.is_solution_usable():
    sys.exit(1)
pp.write_colmap_model(block, out_dir)                  # georeferenced model, ids kept
frames = [pp.FrameRecord(raster=name, camera_id=block.cameras[c].camera_id,
                         eo=block.image_eo(i), sigma0=result.summary.sigma0,
                         covariance=result.images[i].covariance if result.images[i].has_covariance else None)
          for i, (name, c) in enumerate(zip(block.image_names, block.image_cameras))]
pp.write_frames_table(f"{out_dir}/frames.csv", frames, rotation="opk")
print(f"wrote {out_dir}/cameras.txt, images.txt, points3D.txt and frames.csv")
