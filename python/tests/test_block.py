"""The block from numpy arrays, the tables, COLMAP, BAL and Bundler (python/src/block.cc); its
contents as numpy; the table readers and writers; errors on bad input."""

import numpy as np
import pytest

import photopose as pp


@pytest.fixture
def example_files(source_dir):
    examples = source_dir / "examples"
    return examples / "cameras.csv", examples / "points.csv", examples / "marks.csv"


def test_from_arrays_is_the_block_read_from_the_tables(example_files):
    cameras_csv, points_csv, marks_csv = example_files
    read = pp.read_block(cameras_csv, points_csv, marks_csv)
    cameras = pp.read_camera_table(cameras_csv)
    points = pp.read_ground_points(points_csv)
    marks = pp.read_image_marks(marks_csv)
    block = pp.Block.from_arrays(
        cameras, [p.point_id for p in points], np.array([p.position for p in points]),
        [m.raster for m in marks], [m.point_id for m in marks], np.array([m.column_row for m in marks]),
        point_roles=[p.role for p in points],
        mark_accuracy=np.array([m.accuracy if m.accuracy is not None else np.nan for m in marks]),
        mark_camera_ids=[m.camera_id for m in marks])
    assert repr(block) == repr(read)
    assert block.image_names == read.image_names and block.point_ids == read.point_ids
    for name in ("mark_observations", "mark_measured", "surveyed_positions", "mark_images",
                 "mark_points", "image_cameras"):
        np.testing.assert_array_equal(getattr(block, name), getattr(read, name), err_msg=name)
    assert block.mark_units == ["px"] * block.num_marks
    # The same records through Block.from_tables.
    again = pp.Block.from_tables(cameras, points, marks)
    np.testing.assert_array_equal(again.mark_observations, read.mark_observations)


def test_pixel_rows_up_reads_rows_counted_from_the_bottom_edge(tmp_path, example_files):
    cameras_csv, points_csv, marks_csv = example_files
    read = pp.read_block(cameras_csv, points_csv, marks_csv)
    cameras = pp.read_camera_table(cameras_csv)
    marks = pp.read_image_marks(marks_csv)
    n_rows = cameras[0].n_rows
    for mark in marks:
        mark.column_row = [mark.column_row[0], n_rows - mark.column_row[1]]
    pp.write_image_marks(tmp_path / "marks_up.csv", marks)
    # Rows counted up, turned down at the reader: the block of the original marks (to the
    # rounding of n_rows - (n_rows - row)).
    up = pp.read_block(cameras_csv, points_csv, tmp_path / "marks_up.csv", pixel_rows="up")
    np.testing.assert_allclose(up.mark_measured, read.mark_measured, rtol=0, atol=1e-9)
    np.testing.assert_allclose(up.mark_observations, read.mark_observations, rtol=0, atol=1e-9)
    points = pp.read_ground_points(points_csv)
    again = pp.Block.from_tables(cameras, points, marks, pixel_rows="up")
    np.testing.assert_allclose(again.mark_observations, read.mark_observations, rtol=0, atol=1e-9)
    arrays = pp.Block.from_arrays(
        cameras, [p.point_id for p in points], np.array([p.position for p in points]),
        [m.raster for m in marks], [m.point_id for m in marks], np.array([m.column_row for m in marks]),
        point_roles=[p.role for p in points], pixel_rows="up")
    np.testing.assert_allclose(arrays.mark_measured, read.mark_measured, rtol=0, atol=1e-9)
    # Read as rows counted down they are other marks.
    down = pp.read_block(cameras_csv, points_csv, tmp_path / "marks_up.csv")
    assert np.abs(down.mark_measured[:, 1] - read.mark_measured[:, 1]).max() > 1.0
    # A camera without NRows cannot count rows up: refused at the first mark, field Row.
    cameras[0].n_rows = 0
    pp.write_camera_table(tmp_path / "cameras.csv", cameras)
    with pytest.raises(pp.Error, match=r"marks_up.csv:2: Row: rows counted up need NRows"):
        pp.read_block(tmp_path / "cameras.csv", points_csv, tmp_path / "marks_up.csv",
                      pixel_rows="up")
    with pytest.raises(ValueError):
        pp.read_block(cameras_csv, points_csv, marks_csv, pixel_rows="sideways")


def test_block_arrays_and_setters(example_files):
    block = pp.read_block(*example_files)
    n, m = block.num_images, block.num_points
    assert np.isnan(block.image_parameters).all() and block.image_parameters.shape == (n, 6)
    assert block.image_eo(0) is None
    eo = pp.ExteriorOrientation([300000.0, 4100000.0, 120.0], [0.01, 0.02, 0.03])
    block.set_image_eo(0, eo)
    np.testing.assert_array_equal(block.image_parameters[0], eo.parameters)
    np.testing.assert_allclose(block.T_camera_from_ground[0], eo.T_camera_from_ground)
    assert np.isnan(block.T_camera_from_ground[1]).all()
    copy = block.copy()
    copy.set_image_eo(0, None)
    assert block.image_eo(0) is not None and copy.image_eo(0) is None
    parameters = np.tile(eo.parameters, (n, 1))
    parameters[2] = np.nan
    block.set_image_parameters(parameters)
    assert block.image_eo(2) is None and block.image_eo(3) is not None
    block.set_point_positions(np.zeros((m, 3)))
    np.testing.assert_array_equal(block.point_positions, np.zeros((m, 3)))
    block.set_measured_centers(np.ones((n, 3)), accuracy_m=0.05)
    np.testing.assert_array_equal(block.center_accuracies_m, np.full((n, 3), 0.05))
    with pytest.raises(IndexError, match=f"no image {n} in the block"):
        block.image_eo(n)
    with pytest.raises(ValueError, match=f"parameters: expected {n} rows"):
        block.set_image_parameters(np.zeros((n + 1, 6)))
    with pytest.raises(ValueError, match=r"positions: expected an N x 3 array, got shape \(3, 2\)"):
        block.set_point_positions(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="accuracy_m: row 0 is not positive"):
        block.set_measured_centers(np.ones((n, 3)), accuracy_m=-1.0)
    inputs = block.resection_input(0)
    assert len(inputs) > 3 and inputs.approximate is not None


def test_from_arrays_errors_name_the_row():
    camera = pp.FrameCamera(camera_id="c", focal_length_um=8800.0, pixel_size_um=2.4, n_rows=3000,
                            n_columns=4000)
    points = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    with pytest.raises(pp.Error, match="^marks:2: Column: the mark of point 'B' in image 'i' lies"):
        pp.Block.from_arrays([camera], ["A", "B"], points, ["i", "i"], ["A", "B"],
                             np.array([[10.0, 10.0], [50000.0, 20.0]]), point_roles="control")
    with pytest.raises(ValueError, match="marks has 2 rows, mark_rasters 1, mark_point_ids 2"):
        pp.Block.from_arrays([camera], ["A", "B"], points, ["i"], ["A", "B"], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="points_in_ground has 2 rows but point_ids 1"):
        pp.Block.from_arrays([camera], ["A"], points, [], [], np.empty((0, 2)))
    with pytest.raises(ValueError, match="unknown name 'gcp': expected control, check or tie"):
        pp.Block.from_arrays([camera], ["A", "B"], points, [], [], np.empty((0, 2)), point_roles="gcp")
    with pytest.raises(ValueError, match="point_ids: expected a sequence of str, got one str"):
        pp.Block.from_arrays([camera], "AB", points, [], [], [])
    # Nothing at all: the assembly's own refusal, not a crash.
    with pytest.raises(pp.Error, match="no rows"):
        pp.Block.from_arrays([], [], np.empty((0, 3)), [], [], np.empty((0, 2)))
    with pytest.raises(TypeError):
        pp.Block.from_arrays(None, None, None, None, None, None)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_from_arrays_refuses_a_number_that_is_not_finite_as_the_tables_do(tmp_path, value):
    camera = pp.FrameCamera(camera_id="c", focal_length_um=8800.0, pixel_size_um=2.4, n_rows=3000,
                            n_columns=4000)
    points = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    marks = np.array([[10.0, 10.0], [20.0, 20.0]])

    def refusal(**changes):
        arrays = dict(points=points.copy(), marks=marks.copy())
        kwargs = {}
        for name, change in changes.items():
            if name in arrays:
                arrays[name] = change(arrays[name])
            else:
                kwargs[name] = change
        with pytest.raises(pp.Error) as error:
            pp.Block.from_arrays([camera], ["A", "B"], arrays["points"], ["i", "i"], ["A", "B"],
                                 arrays["marks"], **kwargs)
        return str(error.value)

    def at(array, index):
        array[index] = value
        return array

    text = repr(float(value)).lower()
    assert refusal(marks=lambda m: at(m, (1, 1))) == f"marks:2: Row: '{text}' is not a finite number"
    assert refusal(marks=lambda m: at(m, (0, 0))) == f"marks:1: Column: '{text}' is not a finite number"
    assert refusal(marks=lambda m: at(m, (1, 0)), mark_unit="um") == \
        f"marks:2: FilmX: '{text}' is not a finite number"
    assert refusal(points=lambda p: at(p, (1, 2))) == f"points:2: Z: '{text}' is not a finite number"
    frame = pp.FrameRecord(raster="i", camera_id="c",
                           eo=pp.ExteriorOrientation(center_in_ground=(0.0, 0.0, 100.0)))
    bad_frame = pp.FrameRecord(raster="i", camera_id="c",
                               eo=pp.ExteriorOrientation(center_in_ground=(0.0, value, 100.0)))
    assert refusal(frames=[frame, bad_frame]) == \
        f"frames:2: PerspectiveY: '{text}' is not a finite number"
    if not np.isnan(value):  # NaN accuracies mean "not stated"
        assert refusal(mark_accuracy=np.array([1.0, value])) == \
            f"marks:2: Accuracy: '{text}' is not a finite number"
        assert refusal(point_accuracy_m=np.array([[0.01, value, 0.01], [0.01, 0.01, 0.01]])) == \
            f"points:1: AccuracyY: '{text}' is not a finite number"
    # The marks table refuses the same value with the same words, at its own line.
    marks_csv = tmp_path / "marks.csv"
    marks_csv.write_text(f"Raster,PointID,Column,Row\ni,A,10,10\ni,B,20,{text}\n")
    with pytest.raises(pp.Error) as error:
        pp.read_image_marks(marks_csv)
    assert str(error.value) == f"{marks_csv}:3: Row: '{text}' is not a finite number"


def test_table_writers_read_back(tmp_path, example_files):
    cameras = pp.read_camera_table(example_files[0])
    pp.write_camera_table(tmp_path / "cameras.csv", cameras)
    assert (tmp_path / "cameras.csv").read_text() == example_files[0].read_text()
    frame = pp.FrameRecord(raster="img", camera_id=cameras[0].camera_id,
                           eo=pp.ExteriorOrientation([1.0, 2.0, 3.0], [0.1, 0.2, 0.3]),
                           center_accuracy_m=[0.02, 0.02, 0.05])
    pp.write_frames_table(tmp_path / "frames.csv", [frame], rotation="opk")
    text = (tmp_path / "frames.csv").read_text()
    omega = float(text.splitlines()[1].split(",")[5])
    assert omega == pytest.approx(np.degrees(frame.eo.angles_rad("opk")[0]), abs=1e-12)
    back = pp.read_frames_table(tmp_path / "frames.csv", rotation="opk")
    np.testing.assert_allclose(back[0].eo.parameters, frame.eo.parameters, atol=1e-14)
    np.testing.assert_array_equal(back[0].center_accuracy_m, [0.02, 0.02, 0.05])
    points = [pp.GroundPoint(point_id="P", position=[1.0, 2.0, 3.0], role="check")]
    pp.write_ground_points(tmp_path / "points.csv", points)
    assert pp.read_ground_points(tmp_path / "points.csv")[0].role == "check"
    marks = [pp.ImageMark(raster="img", point_id="P", column_row=[10.5, 20.25], accuracy=0.5)]
    pp.write_image_marks(tmp_path / "marks.csv", marks)
    mark = pp.read_image_marks(tmp_path / "marks.csv")[0]
    assert mark.film_um is None and list(mark.column_row) == [10.5, 20.25] and mark.accuracy == 0.5
    with pytest.raises(pp.Error, match="marks.csv:1: PerspectiveX: required column is missing"):
        pp.read_frames_table(tmp_path / "marks.csv")


def test_colmap_bal_bundler_and_gcp_list(shared_data, tmp_path):
    colmap = pp.read_colmap_model(shared_data / "colmap_ar7")
    assert colmap.num_images == 7 and colmap.cameras[0].model == "SIMPLE_RADIAL"
    assert set(colmap.point_roles) == {"tie"} and np.isfinite(colmap.point_positions).all()
    pp.write_colmap_model(colmap, tmp_path / "model")
    again = pp.read_colmap_model(tmp_path / "model")
    np.testing.assert_allclose(again.image_parameters, colmap.image_parameters, atol=1e-12)
    bal = pp.read_bal_problem(shared_data / "bal_dubrovnik" / "dubrovnik-3-7-pre.txt")
    assert (bal.num_images, bal.num_points) == (3, 7) and bal.cameras[0].model == "RADIAL"
    bundler = pp.read_bundler_file(shared_data / "bundler_balbianello" / "Balbianello.out")
    assert bundler.num_points == 544
    gcp = pp.read_gcp_list(shared_data / "odm_br" / "gcp_list.txt")
    assert gcp.crs and len(gcp.points) > 0 and len(gcp.marks) > len(gcp.points)
    with pytest.raises(pp.Error, match="cameras.txt"):
        pp.read_colmap_model(tmp_path)
    with pytest.raises(TypeError, match="expected a path, got None"):
        pp.read_bal_problem(None)


def test_simulated_block_and_its_truth():
    block, truth = pp.simulate_block(seed=1, num_lines=2, images_per_line=4, num_tie_blunders=2)
    assert block.num_images == 8 and truth.image_parameters.shape == (8, 6)
    assert truth.points_m.shape == (block.num_points, 3) and len(truth.blunder_marks) == 2
    options = pp.SyntheticBlockOptions(num_lines=2, images_per_line=4, seed=1, num_tie_blunders=2)
    again, _ = pp.simulate_block(options)
    np.testing.assert_array_equal(again.mark_observations, block.mark_observations)
    with pytest.raises(pp.Error):
        pp.simulate_block(num_lines=0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'lines'"):
        pp.simulate_block(lines=3)
