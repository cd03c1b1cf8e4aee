"""Georeference and adjust a COLMAP model with GNSS camera positions (and ground control).

    python3 adjust_colmap_with_gnss.py COLMAP_DIR GEO_TXT OUT_DIR [GCP_LIST [CHECK,POINTS]]

COLMAP's model lives in its own arbitrary frame; the GNSS positions come as OpenDroneMap's geo.txt
(its first line the CRS, then image x y z [yaw pitch roll] [horizontal vertical accuracy]), the
optional ground control as ODM's gcp_list.txt. georeference_block transforms every input by PROJ
into a local East-North-Up frame, moves the model onto the measurements by a robust similarity,
and adjusts it there with the positions and control weighted by their accuracies; the results go
back into the output CRS (the control's CRS, else the positions' CRS when projected).
"""

import sys

import photopose as pp


def rmse_text(figures):
    """A role's RMSE at one stage (GeoreferenceResult.check_after_adjustment, ...): total_m is None
    when no point has an error at that stage (count 0)."""
    return "n/a" if figures["total_m"] is None else f"{figures['total_m']:.3f} m"


model_dir, geo_txt, out_dir = sys.argv[1:4]
block = pp.read_colmap_model(model_dir)
inputs = pp.GeoreferenceInputs()
inputs.set_positions_from_geo_txt(pp.read_geo_txt(geo_txt), source=geo_txt)
if len(sys.argv) > 4:
    checks = sys.argv[5].split(",") if len(sys.argv) > 5 else []
    inputs.set_control_from_gcp_list(pp.read_gcp_list(sys.argv[4]), check_points=checks, source=sys.argv[4])

options = pp.BundleAdjustmentOptions()
options.accuracies.tie_px = 1.0                        # px, one sigma
options.accuracies.camera_m = [0.05, 0.05, 0.10]       # positions without a stated accuracy (m)
geo, result = pp.georeference_block(block, inputs, bundle_options=options, progress=lambda info: print(
    f"  round {info.round} iteration {info.iteration}: sigma0 {info.sigma0:.3f}"))
print(f"output CRS {geo.out_crs} ({geo.out_crs_name}): {geo.out_crs_reason}")
print(f"similarity: scale {geo.similarity_scale:.6f}, {geo.similarity_inliers} of "
      f"{len(geo.similarity_pairs)} pairs inliers; {geo.positions_matched} positions matched")
print(result.summary.brief_report())
for group in result.groups:
    verdict = "OVERFIT: " + group.message if group.overfit else "ok"
    print(f"{group.group}: n={group.count} rms={group.rms_total:.4f} {group.unit} "
          f"ratio={group.ratio:.2f} redundancy share={group.redundancy_share:.2f} {verdict}")
print(f"check RMSE {rmse_text(geo.check_after_similarity)} after the similarity, "
      f"{rmse_text(geo.check_after_adjustment)} after the adjustment")
if not result.summary.is_solution_usable():
    sys.exit(1)

# The writer of `photopose bundle --out_colmap`: the model's own points and tracks in the local
# ENU frame (ids kept, rejected marks out of the tracks, the control left out), georeference.json
# beside it naming that frame.
pp.write_adjusted_colmap_model(block, out_dir, result, geo)
poses = geo.output_poses(block)                        # X0, Y0, Z0 in the output CRS, angles to its level frame
frames = [pp.FrameRecord(raster=name, camera_id=block.cameras[c].camera_id, srs=geo.out_crs,
                         eo=pp.ExteriorOrientation(poses[i, :3], poses[i, 3:]), sigma0=result.summary.sigma0)
          for i, (name, c) in enumerate(zip(block.image_names, block.image_cameras))]
pp.write_frames_table(f"{out_dir}/frames.csv", frames, rotation="opk")
print(f"wrote {out_dir}/cameras.txt, images.txt, points3D.txt (local frame), georeference.json and "
      f"frames.csv ({geo.out_crs})")
