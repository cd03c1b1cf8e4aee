"""python/examples/ run as a pipeline author would run them, and docs/python.md quotes them as
they are."""

import os
import re
import subprocess
import sys

import numpy as np
import pytest

import photopose as pp


def run_example(source_dir, name, *args):
    env = dict(os.environ)
    done = subprocess.run([sys.executable, str(source_dir / "python" / "examples" / name), *map(str, args)],
                          capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_resect_gcp_marks(source_dir, shared_data):
    out = run_example(source_dir, "resect_gcp_marks.py",
                      shared_data / "odm_br" / "odm_gcp_br_gcp_list_floatxy_raw.txt")
    solved = re.search(r"(\d+) of (\d+) images solved", out)
    assert solved and int(solved.group(1)) >= 5 and int(solved.group(2)) == 10, out
    assert "opk=(" in out and "sigma0=" in out


def test_adjust_colmap_with_gnss(source_dir, tmp_path):
    # A COLMAP model in its own frame (a tenth of the scale, turned, moved) of a synthetic block
    # whose truth is in UTM zone 33N coordinates, and a geo.txt of its true centres with 2 cm noise.
    block, truth = georeference_model(tmp_path)
    rng = np.random.default_rng(1)
    measured = truth.image_parameters[:, :3] + rng.normal(0.0, 0.02, (block.num_images, 3))
    (tmp_path / "geo.txt").write_text("EPSG:32633\n" + "".join(
        f"{name} {x:.4f} {y:.4f} {z:.4f} 0 0 0 0.02 0.02\n" for name, (x, y, z) in zip(block.image_names, measured)))
    out = run_example(source_dir, "adjust_colmap_with_gnss.py", tmp_path / "model", tmp_path / "geo.txt",
                      tmp_path / "out")
    assert "camera_positions: n=24" in out and "round 1 iteration 1" in out, out
    assert "output CRS EPSG:32633" in out and "24 positions matched" in out, out
    adjusted = {f.raster: f for f in pp.read_frames_table(tmp_path / "out" / "frames.csv", rotation="opk")}
    for i, name in enumerate(block.image_names):
        assert adjusted[name].srs == "EPSG:32633"
        error = adjusted[name].eo.center_in_ground - truth.image_parameters[i, :3]
        assert np.abs(error).max() < 0.05, (name, error)
    assert pp.read_colmap_model(tmp_path / "out").num_images == 24


def georeference_model(tmp_path, seed=11):
    """A synthetic block (truth in UTM-like coordinates) written as a COLMAP model in an arbitrary
    frame at tmp_path/model; returns the model block and the truth."""
    block, truth = pp.simulate_block(seed=seed, num_lines=3, images_per_line=8, camera_model="SIMPLE_RADIAL",
                                     num_control_points=0, num_check_points=0, gnss=False)
    s, R, t = 0.1, pp.rotation_from_angles([0.3, -0.2, 1.0]), np.array([5.0, -3.0, 2.0])
    poses = block.image_parameters
    for i in range(block.num_images):
        poses[i] = pp.ExteriorOrientation.from_matrix(pp.rotation_from_angles(poses[i, 3:]) @ R.T,
                                                      s * R @ (poses[i, :3] - [500000.0, 4100000.0, 0.0]) + t).parameters
    block.set_image_parameters(poses)
    block.set_point_positions(s * (block.point_positions - [500000.0, 4100000.0, 0.0]) @ R.T + t)
    pp.write_colmap_model(block, tmp_path / "model")
    return pp.read_colmap_model(tmp_path / "model"), truth


def test_bundle_result_to_numpy(source_dir, tmp_path):
    out = run_example(source_dir, "bundle_result_to_numpy.py", tmp_path / "result.npz")
    assert "check RMSE" in out
    arrays = np.load(tmp_path / "result.npz")
    n = len(arrays["image_names"])
    assert n == 40 and arrays["centers_m"].shape == (n, 3) and arrays["center_sigmas_m"].shape == (n, 3)
    assert np.abs(arrays["centers_m"] - arrays["true_centers_m"]).max() < 0.1
    assert arrays["check_errors_m"].shape == (6, 3)
    assert arrays["mark_residuals"].shape[1] == 2 and len(arrays["normalized_residuals"]) > 0


def test_docs_quote_the_examples_as_they_are(source_dir):
    doc = (source_dir / "docs" / "python.md").read_text()
    for name in ("resect_gcp_marks.py", "adjust_colmap_with_gnss.py", "bundle_result_to_numpy.py"):
        code = (source_dir / "python" / "examples" / name).read_text()
        match = re.search(r"<!-- example: " + re.escape(name) + r" -->\n```python\n(.*?)```", doc, re.S)
        assert match, f"docs/python.md does not quote {name}"
        assert match.group(1) == code, f"docs/python.md quotes an old {name}"
