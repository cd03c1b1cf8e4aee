"""python/examples/ run as a pipeline author would run them, and docs/python.md quotes them as
they are."""

import json
import os
import pathlib
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
    # No check point: the example's line says n/a (the result's None), never 0.000 m.
    assert "check RMSE n/a after the similarity, n/a after the adjustment" in out, out
    adjusted = {f.raster: f for f in pp.read_frames_table(tmp_path / "out" / "frames.csv", rotation="opk")}
    for i, name in enumerate(block.image_names):
        assert adjusted[name].srs == "EPSG:32633"
        error = adjusted[name].eo.center_in_ground - truth.image_parameters[i, :3]
        assert np.abs(error).max() < 0.05, (name, error)
    assert pp.read_colmap_model(tmp_path / "out").num_images == 24


def test_adjust_colmap_with_gnss_and_gcp_list_as_the_cli(source_dir, tmp_path, cli):
    # The documented call with a gcp_list and check points (it raised "the COLMAP extras do not
    # belong to this block" when writing the model), then the CLI on the same inputs: the same
    # figures, frames and written model.
    block, truth, checks = georeference_model(tmp_path, num_control_points=5, num_check_points=4)
    rng = np.random.default_rng(1)
    measured = truth.image_parameters[:, :3] + rng.normal(0.0, 0.02, (block.num_images, 3))
    (tmp_path / "geo.txt").write_text("EPSG:32633\n" + "".join(
        f"{name} {x:.4f} {y:.4f} {z:.4f} 0 0 0 0.02 0.02\n" for name, (x, y, z) in zip(block.image_names, measured)))
    inputs = [tmp_path / "model", tmp_path / "geo.txt"]
    out = run_example(source_dir, "adjust_colmap_with_gnss.py", *inputs, tmp_path / "out", tmp_path / "gcp_list.txt",
                      ",".join(checks))
    figures = re.search(r"check RMSE ([\d.]+) m after the similarity, ([\d.]+) m after the adjustment", out)
    assert figures and "control_points: n=5" in out, out
    # No --camera_accuracy: every position of the geo.txt states its own accuracy, so the example's
    # camera_m weighs none and the CLI refuses the flag (it would have no effect).
    cli("bundle", f"--colmap_model={inputs[0]}", f"--geo={inputs[1]}", f"--gcp_list={tmp_path / 'gcp_list.txt'}",
        f"--check_points={','.join(checks)}", "--tie_accuracy=1",
        f"--out={tmp_path / 'cli.csv'}", f"--out_colmap={tmp_path / 'cli'}", f"--report={tmp_path / 'cli.json'}",
        "--quiet")
    report = json.loads((tmp_path / "cli.json").read_text())["georeference"]
    assert report["check_after_similarity"]["count"] == 4 == report["check_after_adjustment"]["count"]
    assert float(figures.group(1)) == pytest.approx(report["check_after_similarity"]["rmse_total_m"], abs=6e-4)
    assert float(figures.group(2)) == pytest.approx(report["check_after_adjustment"]["rmse_total_m"], abs=6e-4)
    assert float(figures.group(2)) < 0.05 < float(figures.group(1)), out
    example_frames = {f.raster: f for f in pp.read_frames_table(tmp_path / "out" / "frames.csv", rotation="opk")}
    cli_frames = {f.raster: f for f in pp.read_frames_table(tmp_path / "cli.csv")}
    assert sorted(example_frames) == sorted(cli_frames) == sorted(block.image_names)
    for name, frame in cli_frames.items():
        np.testing.assert_allclose(example_frames[name].eo.center_in_ground, frame.eo.center_in_ground, atol=2e-4)
        np.testing.assert_allclose(example_frames[name].eo.angles_seed_rad, frame.eo.angles_seed_rad, atol=1e-6)
        assert example_frames[name].srs == frame.srs == "EPSG:32633"
    # One writer: the model's own points and tracks (no control), the same georeference.json.
    written, cli_written = pp.read_colmap_model(tmp_path / "out"), pp.read_colmap_model(tmp_path / "cli")
    assert written.num_points == cli_written.num_points == block.num_points
    assert written.point_ids == cli_written.point_ids == block.point_ids
    np.testing.assert_array_equal(written.mark_points, cli_written.mark_points)
    np.testing.assert_allclose(written.point_positions, cli_written.point_positions, atol=1e-4)
    frame_json = json.loads((tmp_path / "out" / "georeference.json").read_text())
    assert frame_json == json.loads((tmp_path / "cli" / "georeference.json").read_text())
    assert frame_json["out_crs"] == "EPSG:32633" and "+proj=topocentric" in frame_json[
        "local_to_epsg4979_proj_pipeline_inverse"]


def georeference_model(tmp_path, seed=11, num_control_points=0, num_check_points=0):
    """A synthetic block (truth in UTM-like coordinates) written as a COLMAP model in an arbitrary
    frame at tmp_path/model; returns the model block and the truth. With control and check points,
    the model holds the tie points alone (as COLMAP's would: targets are no features) and
    tmp_path/gcp_list.txt (EPSG:32633) their surveyed coordinates and marks; then returns the check
    point ids too."""
    block, truth = pp.simulate_block(seed=seed, num_lines=3, images_per_line=8, camera_model="SIMPLE_RADIAL",
                                     num_control_points=num_control_points, num_check_points=num_check_points,
                                     gnss=False)
    roles = np.array(block.point_roles)
    surveyed = np.flatnonzero(roles != "tie")
    gcp_lines = [f"{x:.4f} {y:.4f} {z:.4f} {col:.3f} {row:.3f} {block.image_names[image]} {block.point_ids[point]}\n"
                 for image, point, (col, row) in zip(block.mark_images, block.mark_points, block.mark_measured)
                 if point in surveyed for x, y, z in [block.surveyed_positions[point]]]
    s, R, t = 0.1, pp.rotation_from_angles([0.3, -0.2, 1.0]), np.array([5.0, -3.0, 2.0])
    poses = block.image_parameters
    for i in range(block.num_images):
        poses[i] = pp.ExteriorOrientation.from_matrix(pp.rotation_from_angles(poses[i, 3:]) @ R.T,
                                                      s * R @ (poses[i, :3] - [500000.0, 4100000.0, 0.0]) + t).parameters
    block.set_image_parameters(poses)
    block.set_point_positions(s * (block.point_positions - [500000.0, 4100000.0, 0.0]) @ R.T + t)
    pp.write_colmap_model(block, tmp_path / "model")
    if len(surveyed) == 0:
        return pp.read_colmap_model(tmp_path / "model"), truth
    # The written ids are 1..n in block order: the surveyed points leave points3D and the tracks.
    surveyed_ids = {str(p + 1) for p in surveyed}
    points3d = (tmp_path / "model" / "points3D.txt").read_text().splitlines(keepends=True)
    (tmp_path / "model" / "points3D.txt").write_text("".join(
        line for line in points3d if line.startswith("#") or line.split()[0] not in surveyed_ids))
    images = (tmp_path / "model" / "images.txt").read_text().splitlines(keepends=True)
    data_lines = [k for k in range(len(images)) if not images[k].startswith("#")]
    for k in data_lines[1::2]:  # each image's second line: POINTS2D as X Y POINT3D_ID
        entries = images[k].split()
        entries[2::3] = ["-1" if e in surveyed_ids else e for e in entries[2::3]]
        images[k] = " ".join(entries) + "\n"
    (tmp_path / "model" / "images.txt").write_text("".join(images))
    (tmp_path / "gcp_list.txt").write_text("EPSG:32633\n" + "".join(gcp_lines))
    checks = [block.point_ids[p] for p in surveyed if roles[p] == "check"]
    return pp.read_colmap_model(tmp_path / "model"), truth, checks


def test_bundle_result_to_numpy(source_dir, tmp_path):
    out = run_example(source_dir, "bundle_result_to_numpy.py", tmp_path / "result.npz")
    assert "check RMSE" in out
    arrays = np.load(tmp_path / "result.npz")
    n = len(arrays["image_names"])
    assert n == 40 and arrays["centers_m"].shape == (n, 3) and arrays["center_sigmas_m"].shape == (n, 3)
    assert np.abs(arrays["centers_m"] - arrays["true_centers_m"]).max() < 0.1
    assert arrays["check_errors_m"].shape == (6, 3)
    assert arrays["mark_residuals"].shape[1] == 2 and len(arrays["normalized_residuals"]) > 0


def test_docs_quote_the_examples_as_they_are_and_each_is_run_here(source_dir):
    doc = (source_dir / "docs" / "python.md").read_text()
    tests = pathlib.Path(__file__).read_text()
    names = sorted(path.name for path in (source_dir / "python" / "examples").glob("*.py"))
    assert len(names) >= 3, names
    for name in names:
        assert f'run_example(source_dir, "{name}"' in tests, f"no test here runs {name}"
        code = (source_dir / "python" / "examples" / name).read_text()
        match = re.search(r"<!-- example: " + re.escape(name) + r" -->\n```python\n(.*?)```", doc, re.S)
        assert match, f"docs/python.md does not quote {name}"
        assert match.group(1) == code, f"docs/python.md quotes an old {name}"
