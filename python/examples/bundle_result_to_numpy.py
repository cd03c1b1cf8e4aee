"""A bundle result as plain numpy arrays, for plots and notebooks.

    python3 bundle_result_to_numpy.py OUT_NPZ

Adjusts a seeded synthetic block (4 lines of 10 images, 8 control and 6 check points, GNSS
positions, 5 tie-mark blunders of 20 px) and saves what one plots: centres with their standard
deviations, mark residuals and normalized residuals, check-point errors. With matplotlib installed
it also draws the residuals; without, the arrays are the result.
"""

import sys

import numpy as np

import photopose as pp

out = sys.argv[1]
block, truth = pp.simulate_block(seed=7, num_lines=4, images_per_line=10, num_tie_blunders=5)
result = pp.bundle_adjust(block)
print(result.summary.brief_report())

arrays = {
    "image_names": np.array(block.image_names),
    "centers_m": block.image_centers,                             # N x 3, ground frame
    "angles_opk_deg": np.array([block.image_eo(i).angles_deg("opk") for i in range(block.num_images)]),
    "center_sigmas_m": result.image_standard_deviations[:, :3],    # N x 3
    "mark_image": block.mark_images,                               # M, index into images
    "mark_residuals": result.mark_residuals,                       # M x 2, px; NaN: not used
    "check_errors_m": result.point_errors_m[np.array(block.point_roles) == "check"],
    "true_centers_m": truth.image_parameters[:, :3],
}
diagnostics = result.observations                                  # columns, one row per scalar
marks = diagnostics["group"] <= 1                                  # tie and control marks
arrays["normalized_residuals"] = diagnostics["normalized"][marks]
arrays["redundancy_numbers"] = diagnostics["redundancy"][marks]
np.savez(out, **arrays)

used = ~np.isnan(arrays["mark_residuals"]).any(axis=1)
print(f"{used.sum()} marks used, {len(result.rejected_marks)} rejected; "
      f"residual RMS {np.sqrt(np.mean(arrays['mark_residuals'][used] ** 2)):.3f} px; "
      f"check RMSE {result.check_rmse_total_m:.4f} m; "
      f"largest centre error {np.abs(arrays['centers_m'] - arrays['true_centers_m']).max():.4f} m")
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print(f"wrote {out} (matplotlib not installed: no plot)")
else:
    fig, ax = plt.subplots()
    ax.hist(arrays["normalized_residuals"][np.isfinite(arrays["normalized_residuals"])], bins=50)
    ax.set_xlabel("normalized residual w")
    fig.savefig(out.replace(".npz", ".png"))
    print(f"wrote {out} and its histogram")
