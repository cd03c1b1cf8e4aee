"""The bundle adjustment from Python (python/src/bundle.cc) gives the C++ library's block: the
same adjusted poses as the photopose executable on the shared COLMAP model and on a synthetic
block's tables, to 1e-10; options, config, result statistics, progress, errors."""

import numpy as np
import pytest

import photopose as pp

POSE_TOLERANCE = 1e-10


def cli_options():
    """The library's defaults as `photopose bundle` sets them without flags."""
    options = pp.BundleAdjustmentOptions()
    options.statistics.covariances = "full"
    return options


def test_colmap_model_same_poses_as_the_cli(cli, shared_data, tmp_path):
    model = shared_data / "colmap_ar7"
    out = tmp_path / "adjusted"
    cli("bundle", f"--colmap_model={model}", f"--out_colmap={out}", "--quiet")
    block = pp.read_colmap_model(model)
    assert block.num_images == 7 and block.num_cameras >= 1
    pp.initialize_block(block)
    result = pp.bundle_adjust(block, cli_options())
    assert result.summary.termination == "converged"
    assert result.summary.datum == "relative"
    assert result.summary.covariance_datum.startswith("inner constraints on the")
    # Every image has a covariance in the inner-constraint datum; in the adjustment's gauge the
    # first has none.
    assert np.all(np.isfinite(result.image_covariances))
    gauge_options = cli_options()
    gauge_options.statistics.relative_covariance = "first_image"
    gauge_block = pp.read_colmap_model(model)
    pp.initialize_block(gauge_block)
    gauge = pp.bundle_adjust(gauge_block, gauge_options)
    assert "held" in gauge.summary.covariance_datum
    assert np.all(np.isnan(gauge.image_covariances[0]))
    with pytest.raises(ValueError, match="relative_covariance|points"):
        gauge_options.statistics.relative_covariance = "centers"
    expected = pp.read_colmap_model(out)
    np.testing.assert_allclose(block.image_parameters, expected.image_parameters, rtol=0,
                               atol=POSE_TOLERANCE)
    np.testing.assert_allclose(block.point_positions, expected.point_positions, rtol=0,
                               atol=POSE_TOLERANCE)
    # Written back from Python: the CLI's files (ids, keypoints, colours kept), token by token,
    # numbers to 1e-9 (the two runs agree to rounding, not bit for bit: Ceres' threads).
    pp.write_colmap_model(block, tmp_path / "python")
    for name in ("cameras.txt", "images.txt", "points3D.txt"):
        ours = (tmp_path / "python" / name).read_text().split("\n")
        theirs = (out / name).read_text().split("\n")
        assert len(ours) == len(theirs), name
        for line, (a, b) in enumerate(zip(ours, theirs)):
            a, b = a.split(), b.split()
            assert len(a) == len(b), f"{name}:{line + 1}"
            for x, y in zip(a, b):
                try:
                    assert float(x) == pytest.approx(float(y), rel=1e-9, abs=1e-9), f"{name}:{line + 1}"
                except ValueError:
                    assert x == y, f"{name}:{line + 1}"


def synthetic_tables(directory, **options):
    block, truth = pp.simulate_block(seed=5, num_lines=3, images_per_line=6, **options)
    pp.write_block_tables(block, cameras=directory / "cameras.csv", points=directory / "points.csv",
                          marks=directory / "marks.csv", frames=directory / "frames.csv")
    return block, truth


def test_tables_same_poses_as_the_cli(cli, tmp_path):
    synthetic_tables(tmp_path, num_tie_blunders=3)
    out = tmp_path / "adjusted.csv"
    cli("bundle", f"--cameras={tmp_path / 'cameras.csv'}", f"--points={tmp_path / 'points.csv'}",
        f"--marks={tmp_path / 'marks.csv'}", f"--frames={tmp_path / 'frames.csv'}", f"--out={out}",
        "--quiet")
    block = pp.read_block(tmp_path / "cameras.csv", tmp_path / "points.csv", tmp_path / "marks.csv",
                          frames=tmp_path / "frames.csv")
    pp.initialize_block(block)
    result = pp.bundle_adjust(block, cli_options())
    assert result.summary.is_solution_usable()
    assert result.summary.num_rejected_marks >= 1
    frames = {f.raster: f for f in pp.read_frames_table(out)}
    assert len(frames) == block.num_images
    for i, name in enumerate(block.image_names):
        np.testing.assert_allclose(block.image_parameters[i, :3], frames[name].eo.center_in_ground,
                                   rtol=0, atol=POSE_TOLERANCE * 1e3, err_msg=name)  # m at 4e6 m
        np.testing.assert_allclose(block.image_parameters[i, 3:], frames[name].eo.angles_seed_rad,
                                   rtol=0, atol=POSE_TOLERANCE, err_msg=name)


def test_result_statistics_as_numpy(tmp_path):
    block, truth = pp.simulate_block(seed=2, num_lines=3, images_per_line=6, num_check_points=4)
    infos = []
    result = pp.bundle_adjust(block, progress=infos.append)
    summary = result.summary
    assert summary.termination == "converged" and summary.datum == "absolute"
    assert 0.5 < summary.sigma0 < 1.5 and summary.redundancy > 0
    assert infos and infos[-1].iteration >= 1 and all(isinstance(i, pp.BundleIterationInfo) for i in infos)
    assert result.num_check_points == 4 and 0 < result.check_rmse_total_m < 0.2
    n = block.num_images
    assert result.image_covariances.shape == (n, 6, 6) and result.image_adjusted.all()
    sd = result.image_standard_deviations
    np.testing.assert_allclose(sd ** 2, np.diagonal(result.image_covariances, axis1=1, axis2=2))
    # The adjusted block is within a few standard deviations of the truth.
    error = block.image_parameters - truth.image_parameters
    assert np.all(np.abs(error) < 6 * sd)
    errors = result.point_errors_m
    check = np.array([r == "check" for r in block.point_roles])
    assert np.isfinite(errors[check]).all()
    np.testing.assert_allclose(np.sqrt(np.mean(errors[check] ** 2, axis=0)), result.check_rmse_m)
    groups = {g.group: g for g in result.groups}
    assert groups["tie_marks"].count > 0 and groups["tie_marks"].unit == "px"
    columns = result.observations
    assert set(columns) >= {"group", "item", "axis", "residual", "redundancy", "normalized", "rejected"}
    assert len({len(v) for v in columns.values()}) == 1 and len(columns["residual"]) > 0
    assert result.mark_residuals.shape == (block.num_marks, 2)
    report = result.full_report(block)
    assert "tie_marks" in report or "tie marks" in report
    assert repr(result).startswith("BundleAdjustmentResult(")


def test_no_check_point_no_rmse():
    # Without a check point there is no RMSE: NaN, not a zero error.
    block, _ = pp.simulate_block(seed=2, num_lines=2, images_per_line=5, num_check_points=0)
    result = pp.bundle_adjust(block)
    assert result.num_check_points == 0
    assert np.isnan(result.check_rmse_total_m) and np.isnan(result.check_rmse_m).all()
    assert result.num_control_points > 0 and np.isfinite(result.control_rmse_total_m)


def test_cross_validation_update_agrees_with_refit():
    # The default update (one linearised step per left-out control point) against the refit (one
    # adjustment per point), through the module: the same points, errors within a small share.
    block, _ = pp.simulate_block(seed=3, num_lines=3, images_per_line=6)
    result = pp.bundle_adjust(block)
    update = pp.cross_validate_control_points(block, result)
    options = pp.BundleAdjustmentOptions()
    options.statistics.cross_validation = "refit"
    refit = pp.cross_validate_control_points(block, result, options)
    assert update.method == "update" and refit.method == "refit"
    assert update.count == refit.count > 0
    for u, r in zip(update.points, refit.points):
        assert u.point == r.point and u.ok == r.ok
        if u.ok:
            np.testing.assert_allclose(u.error_m, r.error_m, rtol=0.0,
                                       atol=1e-2 * np.linalg.norm(r.error_m) + 1e-6)
    with pytest.raises(ValueError):
        options.statistics.cross_validation = "leave_one_out"


def test_options_config_and_errors():
    block, _ = pp.simulate_block(seed=3, num_lines=2, images_per_line=5)
    options = pp.BundleAdjustmentOptions(
        accuracies=pp.BundleAccuracies(tie_px=0.5, camera_m=[0.05, 0.05, 0.1]),
        robustness=pp.BundleRobustnessOptions(tie_loss="huber"))
    options.solver.linear_solver = "dense_schur"
    assert options.accuracies.tie_px == 0.5 and options.robustness.tie_loss == "huber"
    np.testing.assert_array_equal(options.accuracies.camera_m, [0.05, 0.05, 0.1])
    with pytest.raises(ValueError, match="unknown name 'welsch': expected none, huber"):
        options.robustness.tie_loss = "welsch"
    config = pp.BundleAdjustmentConfig.from_calibration_names(block, ["FocalLength"])
    assert config.calibrated_params == [[0]]
    with pytest.raises(pp.Error, match="Q9"):
        pp.BundleAdjustmentConfig.from_calibration_names(block, ["Q9"])
    result = pp.bundle_adjust(block, options, config)
    assert result.summary.termination == "converged"
    assert [c.names for c in result.calibration] == [["FocalLength"]]
    bad = pp.BundleAdjustmentOptions()
    bad.robustness.max_rejection_rounds = -1
    with pytest.raises(pp.Error):
        pp.bundle_adjust(block, bad)
    # What needs the statistics is refused without them, as the CLI refuses --snoop with
    # --statistics=none (never skipped in silence).
    needs = pp.BundleAdjustmentOptions()
    needs.statistics.covariances = "none"
    needs.robustness.snoop = True
    with pytest.raises(pp.Error, match=r"data snooping \(robustness.snoop\) needs the statistics"):
        pp.bundle_adjust(block, needs)
    needs.robustness.snoop = False
    needs.statistics.estimate_accuracies = True
    with pytest.raises(pp.Error, match=r"statistics.estimate_accuracies\) needs the statistics"):
        pp.bundle_adjust(block, needs)
    with pytest.raises(TypeError, match="progress: expected a callable"):
        pp.bundle_adjust(block, progress=3)
    with pytest.raises(TypeError):
        pp.bundle_adjust(None)


def test_progress_exception_is_raised_after_the_adjustment():
    block, _ = pp.simulate_block(seed=4, num_lines=2, images_per_line=5)
    calls = []

    def stop(info):
        calls.append(info.iteration)
        raise KeyboardInterrupt("stop")

    start = block.image_parameters.copy()
    with pytest.raises(KeyboardInterrupt, match="stop"):
        pp.bundle_adjust(block, progress=stop)
    assert len(calls) == 1  # not called again after it raised
    np.testing.assert_array_equal(block.image_parameters, start)  # the adjustment stopped there


@pytest.mark.parametrize("solver, first_iteration", [("ceres", 0), ("taylor", 1)])
def test_progress_returning_false_cancels_the_adjustment(solver, first_iteration):
    block, _ = pp.simulate_block(seed=4, num_lines=2, images_per_line=5)
    start = block.image_parameters.copy()
    calls = []

    def stop_after_two(info):
        calls.append(info.iteration)
        return len(calls) < 2  # None (no return) or True goes on; False stops

    result = pp.bundle_adjust(block, progress=stop_after_two, solver=solver)
    assert result.summary.termination == "cancelled"
    assert "cancelled by the progress hook after iteration" in result.summary.message
    assert calls == [first_iteration, first_iteration + 1]
    np.testing.assert_array_equal(block.image_parameters, start)
    # The same block adjusted without stopping: a callback returning None goes on.
    assert (pp.bundle_adjust(block, progress=lambda info: None, solver=solver).summary.termination
            == "converged")


def test_bundle_adjust_releases_the_gil(assert_releases_gil):
    block, _ = pp.simulate_block(seed=6, num_lines=4, images_per_line=12)
    options = pp.BundleAdjustmentOptions()
    options.solver.num_threads = 1
    assert_releases_gil(lambda: pp.bundle_adjust(block, options))


def test_control_points_with_accuracy_zero_are_held_fixed(tmp_path):
    """AccuracyX/Y/Z 0 in the points table (read by read_ground_points and read_block) holds a
    control point fixed: it stays on its survey and its group is "fixed", without a verdict; a row
    mixing 0 and non-zero is refused naming file, line and field, and from_arrays refuses it too."""
    synthetic_tables(tmp_path)
    lines = (tmp_path / "points.csv").read_text().splitlines()
    header = lines[0].split(",")
    role, accuracy = header.index("Role"), header.index("AccuracyX")
    rows = [line.split(",") for line in lines[1:]]
    for row in rows:
        if row[role] == "control":
            row[accuracy:accuracy + 3] = ["0", "0", "0"]
    (tmp_path / "points0.csv").write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    points = pp.read_ground_points(tmp_path / "points0.csv")
    fixed = [p.point_id for p in points if p.role == "control"]
    assert fixed and all(list(p.accuracy_m) == [0, 0, 0] for p in points if p.role == "control")
    block = pp.read_block(tmp_path / "cameras.csv", tmp_path / "points0.csv", tmp_path / "marks.csv",
                          frames=tmp_path / "frames.csv")
    surveyed = block.surveyed_positions.copy()
    pp.initialize_block(block)
    result = pp.bundle_adjust(block, cli_options())
    assert result.summary.is_solution_usable()
    groups = {g.group: g for g in result.groups}
    control = groups["control_points"]
    assert control.fixed and control.num_fixed == len(fixed) and control.count == 0
    assert not control.overfit and control.message == ""
    held = [i for i, (name, r) in enumerate(zip(block.point_ids, block.point_roles))
            if r == "control" and name in fixed]
    np.testing.assert_array_equal(block.point_positions[held], surveyed[held])

    first = next(i for i, r in enumerate(rows) if r[role] == "control")
    rows[first][accuracy + 1] = "0.01"
    (tmp_path / "mixed.csv").write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    with pytest.raises(pp.Error, match=rf"mixed\.csv:{first + 2}: AccuracyY: 0\.01 beside AccuracyX 0"):
        pp.read_ground_points(tmp_path / "mixed.csv")
    camera = pp.FrameCamera(camera_id="c", focal_length_um=8800.0, pixel_size_um=2.4, n_rows=3000,
                            n_columns=4000)
    with pytest.raises(ValueError, match="point_accuracy_m: row 1 is neither positive on every axis"):
        pp.Block.from_arrays([camera], ["A", "B"], np.zeros((2, 3)), [], [], np.empty((0, 2)),
                             point_accuracy_m=np.array([[0.0, 0.0, 0.0], [0.0, 0.01, 0.0]]))


def test_taylor_solver_reaches_the_same_minimum_and_statistics(shared_data):
    # The same simulated block twice (the generator is deterministic per seed).
    ceres_block, _ = pp.simulate_block(seed=3, num_lines=3, images_per_line=5, num_check_points=3)
    taylor_block, _ = pp.simulate_block(seed=3, num_lines=3, images_per_line=5, num_check_points=3)
    ceres = pp.bundle_adjust(ceres_block)
    infos = []
    taylor = pp.bundle_adjust(taylor_block, solver="taylor", progress=infos.append)
    assert ceres.summary.termination == taylor.summary.termination == "converged"
    assert infos and infos[-1].iteration >= 1
    # One minimum (Ceres stops within about 1e-6 m of it) and one set of statistics.
    np.testing.assert_allclose(taylor.summary.final_cost, ceres.summary.final_cost, rtol=1e-8)
    np.testing.assert_allclose(taylor_block.image_parameters[:, :3],
                               ceres_block.image_parameters[:, :3], rtol=0, atol=1e-5)
    np.testing.assert_allclose(taylor_block.image_parameters[:, 3:],
                               ceres_block.image_parameters[:, 3:], rtol=0, atol=1e-7)
    np.testing.assert_allclose(taylor.image_standard_deviations, ceres.image_standard_deviations,
                               rtol=1e-4)
    np.testing.assert_allclose(taylor.check_rmse_m, ceres.check_rmse_m, rtol=1e-4)
    ratios = {g.group: g.ratio for g in ceres.groups}
    for g in taylor.groups:
        np.testing.assert_allclose(g.ratio, ratios[g.group], rtol=1e-4, err_msg=g.group)
    assert len(taylor.observations["redundancy"]) == len(ceres.observations["redundancy"])
    np.testing.assert_allclose(np.sum(taylor.observations["redundancy"]),
                               taylor.summary.redundancy, rtol=1e-6)
    # A real COLMAP model (SIMPLE_RADIAL, a relative block): the Taylor solver works in pixels
    # through the model's derivative and reaches the Ceres minimum in COLMAP's gauge.
    colmap_ceres = pp.read_colmap_model(shared_data / "colmap_ar7")
    colmap_taylor = pp.read_colmap_model(shared_data / "colmap_ar7")
    pp.initialize_block(colmap_ceres)
    pp.initialize_block(colmap_taylor)
    first_pose = colmap_taylor.image_parameters[0].copy()
    keep_all = pp.BundleAdjustmentOptions(
        robustness=pp.BundleRobustnessOptions(rejection_threshold=0.0))
    on_ceres = pp.bundle_adjust(colmap_ceres, keep_all)
    on_taylor = pp.bundle_adjust(colmap_taylor, keep_all, solver="taylor")
    assert on_ceres.summary.termination == on_taylor.summary.termination == "converged"
    assert (on_ceres.summary.solver, on_taylor.summary.solver) == ("ceres", "taylor")
    assert on_taylor.summary.redundancy == on_ceres.summary.redundancy
    np.testing.assert_allclose(on_taylor.summary.final_cost, on_ceres.summary.final_cost, rtol=1e-6)
    np.testing.assert_array_equal(colmap_taylor.image_parameters[0], first_pose)
    # Self-calibration (the model's f) on the Taylor path reaches the Ceres minimum too.
    calibrate_f = pp.BundleAdjustmentConfig.from_calibration_names(colmap_taylor, ["f"])
    f_ceres = pp.bundle_adjust(colmap_ceres, keep_all, calibrate_f)
    f_taylor = pp.bundle_adjust(colmap_taylor, keep_all, calibrate_f, solver="taylor")
    assert f_ceres.summary.termination == f_taylor.summary.termination == "converged"
    assert f_taylor.summary.redundancy == f_ceres.summary.redundancy
    np.testing.assert_allclose(f_taylor.summary.final_cost, f_ceres.summary.final_cost, rtol=1e-6)
    # An unknown solver is refused by name.
    with pytest.raises(ValueError, match="levmar"):
        pp.bundle_adjust(taylor_block, solver="levmar")


def test_rejected_check_marks(tmp_path):
    """A check point's mark off by 40 px is rejected by the w-test of the check point's
    intersection: result.rejected_check_marks names it, with its residual."""
    block, _ = pp.simulate_block(seed=7, num_lines=4, images_per_line=10)
    tables = {name: tmp_path / f"{name}.csv" for name in ("cameras", "points", "marks", "frames")}
    pp.write_block_tables(block, **tables)
    clean = pp.bundle_adjust(block)
    assert clean.rejected_check_marks == []
    assert clean.weakly_determined == []  # a well-determined block lists none
    roles = dict(zip(block.point_ids, block.point_roles))
    lines = tables["marks"].read_text().splitlines()
    header = lines[0].split(",")
    raster_column, point_column, x_column = (header.index(n) for n in ("Raster", "PointID", "Column"))
    row = next(k for k, line in enumerate(lines[1:], 1) if roles[line.split(",")[point_column]] == "check")
    fields = lines[row].split(",")
    fields[x_column] = repr(float(fields[x_column]) + 40.0)
    lines[row] = ",".join(fields)
    tables["marks"].write_text("\n".join(lines) + "\n")
    blundered = pp.read_block(tables["cameras"], tables["points"], tables["marks"], frames=tables["frames"])
    result = pp.bundle_adjust(blundered)
    assert len(result.rejected_check_marks) == 1, result.rejected_check_marks
    rejected = result.rejected_check_marks[0]
    assert blundered.image_names[blundered.mark_images[rejected.mark]] == fields[raster_column]
    assert blundered.point_ids[blundered.mark_points[rejected.mark]] == fields[point_column]
    # In the mark's own unit, pixels (the camera model's film micrometres divided by the mark's
    # micrometres per pixel).
    assert rejected.normalized > 3.0 and 20.0 < abs(rejected.residual[0]) < 40.0
    assert abs(rejected.residual[1]) < abs(rejected.residual[0]) / 4.0
    assert repr(rejected).startswith(f"BundleRejectedCheckMark(mark={rejected.mark}, normalized=")


def test_check_points_say_whether_their_covariance_is_complete():
    # With the statistics, a check point's covariance carries the images' own; without, it is the
    # intersection's alone, too small to judge its error by (the reports leave it untested).
    for covariances, complete in (("full", True), ("none", False)):
        block, _ = pp.simulate_block(seed=4, num_lines=2, images_per_line=5, num_check_points=2)
        options = pp.BundleAdjustmentOptions()
        options.statistics.covariances = covariances
        result = pp.bundle_adjust(block, options)
        checks = [r for r, role in zip(result.points, block.point_roles) if role == "check"]
        assert len(checks) == 2
        assert all(r.has_covariance and r.covariance_complete == complete for r in checks)
