"""Resection from Python (python/src/resection.cc) gives the C++ library's poses: the same as the
photopose executable's frames tables on the bundled example and on OpenDroneMap's gcp_list, to
1e-10; from numpy arrays; with clear errors on bad input; without holding the GIL."""

import numpy as np
import pytest

import photopose as pp

# The CLI writes every number as the shortest text that reads back exactly, and its angles in
# degrees through the same conversion as ExteriorOrientation.angles_deg: equality to rounding.
POSE_TOLERANCE = 1e-10
ODM_CAMERA = "CameraID,FocalLength,PixelSize,NColumns,NRows\nSX260HS,4500,1.5495867768595042,4000,3000\n"


def frames_by_raster(path):
    return {f.raster: f for f in pp.read_frames_table(path)}


def assert_same_poses(block, images, results, cli_frames):
    solved = {block.image_names[i]: r for i, r in zip(images, results) if r.success}
    assert set(solved) == set(cli_frames), "the CLI and Python solved different images"
    assert solved, "nothing solved: the comparison would prove nothing"
    for raster, result in solved.items():
        frame = cli_frames[raster]
        np.testing.assert_allclose(result.eo.center_in_ground, frame.eo.center_in_ground,
                                   rtol=0, atol=POSE_TOLERANCE * 1e3, err_msg=raster)  # m at 4e6 m
        np.testing.assert_allclose(result.eo.angles_seed_rad, frame.eo.angles_seed_rad,
                                   rtol=0, atol=POSE_TOLERANCE, err_msg=raster)
        sigma0 = dict(frame.extra_columns).get("Sigma0") or frame.sigma0
        assert float(sigma0) == pytest.approx(result.sigma0, rel=1e-12)


def test_example_block_same_poses_as_the_cli(cli, source_dir, tmp_path):
    examples = source_dir / "examples"
    out = tmp_path / "frames.csv"
    cli("resect", f"--cameras={examples / 'cameras.csv'}", f"--points={examples / 'points.csv'}",
        f"--marks={examples / 'marks.csv'}", f"--out={out}")
    block = pp.read_block(examples / "cameras.csv", examples / "points.csv", examples / "marks.csv")
    images, inputs = block.resection_inputs()
    results = pp.resect_images(inputs)
    assert len(results) == len(inputs) == 12
    assert_same_poses(block, images, results, frames_by_raster(out))
    # One image alone, as ResectImage (no per-image seed): the same pose with every mark known.
    single = pp.resect(inputs[0])
    np.testing.assert_allclose(single.eo.parameters, results[0].eo.parameters, atol=1e-8)


def test_opendronemap_gcp_list_same_poses_as_the_cli(cli, shared_data, tmp_path):
    cameras = tmp_path / "cameras.csv"
    cameras.write_text(ODM_CAMERA)
    gcp = shared_data / "odm_br" / "odm_gcp_br_gcp_list_floatxy_raw.txt"
    out = tmp_path / "frames.csv"
    done = cli("resect", f"--cameras={cameras}", f"--gcp_list={gcp}", f"--out={out}",
               "--default_accuracy=2", check=False)
    assert done.returncode in (0, 1), done.stderr
    block = pp.read_block(cameras, gcp_list=gcp)
    assert block.crs.startswith("EPSG:") or block.crs.startswith("WGS") or block.crs
    images, inputs = block.resection_inputs(default_accuracy=2.0)
    results = pp.resect_images(inputs, num_threads=1)
    assert_same_poses(block, images, results, frames_by_raster(out))


def synthetic_image(seed=3, n=12, noise_um=1.0):
    rng = np.random.default_rng(seed)
    eo = pp.ExteriorOrientation([1000.0, 2000.0, 300.0], np.radians([1.0, -2.0, 30.0]))
    points = np.c_[rng.uniform(850, 1150, (n, 2)) + [0, 1000], rng.uniform(0, 30, n)]
    focal = 24000.0
    xy = pp.project_to_image_plane(eo, points, focal) + rng.normal(0.0, noise_um, (n, 2))
    return eo, points, xy, focal


def test_resection_from_numpy_arrays():
    truth, points, xy, focal = synthetic_image()
    xy[4] += [80.0, -60.0]  # a blunder of 100 um
    result = pp.resect(pp.ResectionInput(xy, points, focal, sigma=1.0, units="um",
                                         point_ids=[f"P{i}" for i in range(len(xy))]))
    assert result.success, result.summary.message
    assert result.mark_status[4] in ("outlier", "rejected")
    assert not result.inliers[4] and result.inliers.sum() == len(xy) - 1
    assert result.num_inliers == len(xy) - 1 and result.degrees_of_freedom == 2 * (len(xy) - 1) - 6
    # Within 5 standard deviations of the truth, and the covariance is the one it reports.
    error = result.eo.parameters - truth.parameters
    assert np.all(np.abs(error) < 5 * result.standard_deviations)
    np.testing.assert_allclose(np.sqrt(np.diag(result.covariance)), result.standard_deviations)
    assert result.residuals.shape == (len(xy), 2) and result.covariance.shape == (6, 6)
    assert result.summary.termination == "converged" and result.summary.is_solution_usable()
    assert repr(result).startswith("ResectionResult(weak" if result.weak else "ResectionResult(solved")
    # From an approximate pose, every mark a candidate: the same solution.
    again = pp.resect(pp.ResectionInput(xy, points, focal, sigma=1.0, approximate=truth))
    assert again.summary.used_approximate
    np.testing.assert_allclose(again.eo.parameters, result.eo.parameters, atol=1e-9)


def test_covariance_is_a_priori_with_stated_accuracy_and_scaled_without():
    """The library's one rule (PoseCovarianceFactor): with sigma stated the covariance is N^-1, sigma0
    reported beside; without, sigma0^2 N^-1, and few degrees of freedom say how far to trust it."""
    _, points, xy, focal = synthetic_image(seed=5, n=5)
    stated = pp.resect(pp.ResectionInput(xy, points, focal, sigma=1.0, units="um"))
    estimated = pp.resect(pp.ResectionInput(xy, points, focal, units="um"))
    assert stated.success and estimated.success, (stated.summary.message, estimated.summary.message)
    assert stated.accuracy_stated and not estimated.accuracy_stated
    assert stated.covariance_factor == 1.0 and stated.sigma_upper_factor == 1.0
    assert estimated.covariance_factor == pytest.approx(estimated.sigma0 ** 2, rel=1e-12)
    np.testing.assert_allclose(estimated.covariance, estimated.sigma0 ** 2 * stated.covariance,
                               rtol=1e-6, atol=1e-6 * np.abs(estimated.covariance).max())
    assert estimated.degrees_of_freedom == 4 and estimated.sigma_upper_factor > 2.0
    assert any(w.startswith("uncertain sigmas:") for w in estimated.warnings)


def test_options_as_keywords_and_attributes():
    options = pp.ResectionOptions(allow_no_redundancy=True,
                                  test=pp.OutlierTestOptions(confidence=0.99))
    assert options.allow_no_redundancy and options.test.confidence == 0.99
    assert options.refinement.solver == "ceres" and options.consensus.ransac.max_trials == 10000
    options.refinement.solver = "taylor"
    options.refinement.loss = "huber"
    assert options.refinement.solver == "taylor" and "loss='huber'" in repr(options)
    truth, points, xy, focal = synthetic_image(noise_um=0.5)
    three = pp.ResectionInput(xy[:3], points[:3], focal, sigma=0.5, approximate=truth)
    # The Taylor solver has no robust loss: refused, not ignored.
    with pytest.raises(pp.Error, match="no robust loss"):
        pp.resect(three, options)
    options.refinement.loss = "none"
    # Three marks: allowed without redundancy, the approximate pose choosing among P3P's poses.
    result = pp.resect(three, options)
    assert result.success and not result.has_covariance and result.weak, result.summary.message
    with pytest.raises(TypeError, match="unexpected keyword argument 'confidence'"):
        pp.ResectionOptions(confidence=0.9)
    with pytest.raises(ValueError, match="unknown name 'newton': expected ceres, taylor or taylor_as_printed"):
        options.refinement.solver = "newton"


def test_failures_are_results_not_exceptions():
    truth, points, xy, focal = synthetic_image()
    result = pp.resect(pp.ResectionInput(xy[:3], points[:3], focal, sigma=1.0))
    assert not result.success and result.summary.termination == "failure"
    assert "redundancy" in result.summary.message
    assert repr(result).startswith("ResectionResult(not_solved")
    empty = pp.resect(pp.ResectionInput(np.empty((0, 2)), np.empty((0, 3)), focal))
    assert not empty.success and empty.summary.message


def test_bad_input_raises_clear_errors():
    truth, points, xy, focal = synthetic_image()
    with pytest.raises(ValueError, match="image_plane has 12 rows but points_in_ground 11"):
        pp.ResectionInput(xy, points[:11], focal)
    with pytest.raises(ValueError, match=r"image_plane: expected an N x 2 array, got None"):
        pp.ResectionInput(None, points, focal)
    with pytest.raises(ValueError, match=r"sigma: expected a vector of 12 numbers, got shape \(3,\)"):
        pp.ResectionInput(xy, points, focal, sigma=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="unknown name 'mm': expected px or um"):
        pp.ResectionInput(xy, points, focal, units="mm")
    with pytest.raises(TypeError):
        pp.resect(None)
    bad = pp.ResectionOptions(test=pp.OutlierTestOptions(confidence=1.5))
    with pytest.raises(pp.Error, match="^invalid options: "):
        pp.resect(pp.ResectionInput(xy, points, focal), bad)
    with pytest.raises(ValueError, match="num_threads must be >= 0"):
        pp.resect_images([], num_threads=-1)
    assert pp.resect_images([]) == []


def test_reader_errors_carry_the_library_message(cli, source_dir, tmp_path):
    marks = tmp_path / "marks.csv"
    marks.write_text("Raster,PointID,Column,Row\nimg_0001,P0001,abc,2\n")
    examples = source_dir / "examples"
    with pytest.raises(pp.Error) as raised:
        pp.read_block(examples / "cameras.csv", examples / "points.csv", marks)
    assert str(raised.value) == f"{marks}:2: Column: 'abc' is not a number"
    done = cli("resect", f"--cameras={examples / 'cameras.csv'}", f"--points={examples / 'points.csv'}",
               f"--marks={marks}", f"--out={tmp_path / 'f.csv'}", check=False)
    assert done.returncode == 2 and str(raised.value) in done.stderr
    with pytest.raises(pp.Error, match="no_such_file"):
        pp.read_block(tmp_path / "no_such_file.csv", examples / "points.csv", examples / "marks.csv")


def test_batch_resection_releases_the_gil(source_dir, assert_releases_gil):
    examples = source_dir / "examples"
    block = pp.read_block(examples / "cameras.csv", examples / "points.csv", examples / "marks.csv")
    _, inputs = block.resection_inputs()
    assert_releases_gil(lambda: pp.resect_images(inputs * 40, num_threads=1))


def blundered_inputs(n, seed=5):
    """n images of 25 control marks each, four of them blunders: too many samples to try them all
    (C(25, 3) > max_exhaustive_samples), so the RANSAC trials depend on the image's seed."""
    rng = np.random.default_rng(seed)
    inputs = []
    for i in range(n):
        truth, points, xy, focal = synthetic_image(seed=int(rng.integers(1 << 30)), n=25)
        xy[:4] += rng.uniform(60.0, 120.0, (4, 2))
        inputs.append(pp.ResectionInput(xy, points, focal, sigma=1.0, raster=f"img_{i}"))
    return inputs


def outcome(results):
    return [(r.success, tuple(r.eo.parameters), r.sigma0, r.summary.ransac_trials) for r in results]


def test_batch_resection_progress():
    inputs = blundered_inputs(150)
    alone = pp.resect_images(inputs, num_threads=2)
    for threads in (1, 2):
        infos = []
        results = pp.resect_images(inputs, num_threads=threads, progress=infos.append)
        done = [info.images_done for info in infos]
        # Throttled: a call when 1 % of the batch (here 2 images) has finished or 0.1 s has passed
        # since the last one, and at the end.
        assert 2 < len(infos) <= len(inputs) // 2 + infos[-1].elapsed_seconds / 0.1 + 2, done
        assert done[-1] == len(inputs), done
        assert all(a < b for a, b in zip(done, done[1:])), done
        assert {info.images_total for info in infos} == {len(inputs)}
        elapsed = [info.elapsed_seconds for info in infos]
        assert elapsed[0] >= 0.0 and all(a <= b for a, b in zip(elapsed, elapsed[1:]))
        assert repr(infos[-1]).startswith(f"ResectionProgress(images_done={len(inputs)}, images_total=")
        # One call, every image with its seed: the same results, bit for bit.
        assert outcome(results) == outcome(alone)
        assert not any(r.cancelled for r in results)
    # The comparison can fail: another seed gives other trials.
    other = pp.ResectionOptions()
    other.consensus.ransac.seed += 1
    assert outcome(pp.resect_images(inputs, other, num_threads=2)) != outcome(alone)
    calls = []
    assert pp.resect_images([], progress=calls.append) == [] and calls == []
    with pytest.raises(TypeError, match="progress: expected a callable taking a ResectionProgress"):
        pp.resect_images(inputs, progress=3)


def test_batch_resection_progress_exception_is_raised():
    inputs = blundered_inputs(100)
    calls = []

    def stop(info):
        calls.append(info.images_done)
        raise KeyboardInterrupt("stop")

    with pytest.raises(KeyboardInterrupt, match="stop"):
        pp.resect_images(inputs, num_threads=1, progress=stop)
    assert calls == [1]  # after the first image (1 % of 100), and not again: the batch cancelled
    # The module works on after it.
    assert outcome(pp.resect_images(inputs[:3], num_threads=1)) == outcome(
        pp.resect_images(inputs[:3], num_threads=1, progress=lambda info: None))


def test_batch_resection_progress_returning_false_cancels():
    inputs = blundered_inputs(60)
    alone = pp.resect_images(inputs, num_threads=1)
    calls = []

    def enough(info):
        calls.append(info.images_done)
        return info.images_done < 10

    results = pp.resect_images(inputs, num_threads=1, progress=enough)
    assert calls == list(range(1, 11))  # 1 % of 60 is one image
    assert [r.cancelled for r in results] == [False] * 10 + [True] * 50
    assert outcome(results[:10]) == outcome(alone[:10])
    for r in results[10:]:
        assert not r.success and r.summary.message.startswith("cancelled")
        assert r.summary.termination == "cancelled"
        assert r.num_inliers == 0 and len(r.inliers) == 0
        assert repr(r).startswith("ResectionResult(cancelled, message='cancelled")
    # True and None go on.
    assert outcome(pp.resect_images(inputs, num_threads=2, progress=lambda info: True)) == outcome(alone)


def test_batch_resection_with_progress_releases_the_gil(source_dir, assert_releases_gil):
    examples = source_dir / "examples"
    block = pp.read_block(examples / "cameras.csv", examples / "points.csv", examples / "marks.csv")
    _, inputs = block.resection_inputs()
    infos = []
    assert_releases_gil(lambda: pp.resect_images(inputs * 40, num_threads=1, progress=infos.append))
    assert infos[-1].images_done == 480
