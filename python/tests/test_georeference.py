"""Georeferencing from Python: the inputs (geo.txt, gcp_list.txt, arrays, GPS tags), the call, its
result in the output CRS, and the same answer as `photopose bundle --colmap_model --geo`."""

import numpy as np
import pytest

import photopose as pp
from test_examples import georeference_model


def write_geo_txt(path, names, xyz, sigma):
    path.write_text("EPSG:32633\n" + "".join(
        f"{n} {x:.4f} {y:.4f} {z:.4f} 0 0 0 {sigma[0]} {sigma[2]}\n" for n, (x, y, z) in zip(names, xyz)))


@pytest.fixture
def scene(tmp_path):
    block, truth = georeference_model(tmp_path, seed=7)
    rng = np.random.default_rng(3)
    measured = truth.image_parameters[:, :3] + rng.normal(0.0, 0.03, (block.num_images, 3))
    write_geo_txt(tmp_path / "geo.txt", block.image_names, measured, (0.03, 0.03, 0.05))
    return block, truth, measured


def test_geo_txt_and_arrays_give_the_same_inputs(scene, tmp_path):
    block, _, measured = scene
    geo = pp.read_geo_txt(tmp_path / "geo.txt")
    assert geo.crs == "EPSG:32633" and len(geo.records) == 24
    assert geo.records[0].yaw_pitch_roll_deg is not None and geo.records[0].horizontal_accuracy_m == 0.03
    from_file = pp.GeoreferenceInputs()
    from_file.set_positions_from_geo_txt(geo)
    from_arrays = pp.GeoreferenceInputs()
    sigma = np.tile([0.03, 0.03, 0.05], (24, 1))
    from_arrays.set_positions("EPSG:32633", block.image_names, np.round(measured, 4), sigma)
    assert from_file.positions_crs == from_arrays.positions_crs
    for a, b in zip(from_file.positions, from_arrays.positions):
        assert a.image == b.image
        np.testing.assert_allclose(a.position, b.position, atol=1e-9)
        np.testing.assert_allclose(a.accuracy_m, b.accuracy_m)


def test_same_poses_as_the_cli(scene, tmp_path, cli):
    block, truth, _ = scene
    inputs = pp.GeoreferenceInputs()
    inputs.set_positions_from_geo_txt(pp.read_geo_txt(tmp_path / "geo.txt"))
    calls = []
    geo, result = pp.georeference_block(block, inputs, progress=calls.append)
    assert calls and result.summary.termination == "converged"
    assert geo.out_crs == "EPSG:32633" and geo.positions_matched == 24 and geo.evaluated
    # Its yaw/pitch/roll are all 0 ("not available" in ODM): nothing read and left unused.
    assert inputs.attitudes_not_used == 0 and geo.inputs_not_used == []
    assert "projected" in geo.out_crs_reason or "positions" in geo.out_crs_reason, geo.out_crs_reason
    assert 0.09 < geo.similarity_scale < 0.11 or 9.0 < geo.similarity_scale < 11.0
    poses = geo.output_poses(block)
    assert poses.shape == (24, 6)
    assert np.abs(poses[:, :3] - truth.image_parameters[:, :3]).max() < 0.08

    cli("bundle", f"--colmap_model={tmp_path / 'model'}", f"--geo={tmp_path / 'geo.txt'}",
        f"--out={tmp_path / 'cli.csv'}", "--quiet")
    frames = {f.raster: f for f in pp.read_frames_table(tmp_path / "cli.csv")}
    for i, name in enumerate(block.image_names):
        np.testing.assert_allclose(frames[name].eo.center_in_ground, poses[i, :3], atol=2e-4)
        np.testing.assert_allclose(frames[name].eo.angles_seed_rad, poses[i, 3:], atol=1e-6)
    # Local frame <-> output CRS: the block's centres, moved out, are the output poses' centres.
    np.testing.assert_allclose(geo.to_output_crs(block.image_centers), poses[:, :3], atol=1e-6)
    assert "out_crs='EPSG:32633'" in repr(geo)
    # No control and no check point: no RMSE at any stage, None rather than a 0 that reads as no
    # error; the repr names no figure.
    for figures in (geo.control_after_similarity, geo.check_after_similarity,
                    geo.control_after_adjustment, geo.check_after_adjustment):
        assert figures == {"count": 0, "rmse_m": None, "total_m": None}, figures
    assert "control=0, check=0)" in repr(geo) and "rmse" not in repr(geo), repr(geo)


def test_bad_inputs_raise_with_the_library_message(scene, tmp_path):
    block, _, measured = scene
    inputs = pp.GeoreferenceInputs()
    inputs.set_positions("EPSG:999999", block.image_names, measured)
    with pytest.raises(pp.Error, match="EPSG:999999"):
        pp.georeference_block(block.copy(), inputs)
    with pytest.raises(ValueError, match="positions: 3 rows for 24 images"):
        inputs.set_positions("EPSG:32633", block.image_names, measured[:3])
    with pytest.raises(ValueError, match="positions"):
        inputs.set_positions("EPSG:32633", block.image_names, measured[:, :2])
    with pytest.raises(pp.Error, match="'nope' is not a point"):
        inputs.set_control_from_gcp_list(pp.GcpList(crs="EPSG:32633"), check_points=["nope"])
    (tmp_path / "not_an_image.jpg").write_text("hello\n")
    with pytest.raises(pp.Error, match="not_an_image.jpg"):
        pp.read_image_gps(tmp_path / "not_an_image.jpg")
    with pytest.raises(pp.Error, match="not a directory"):
        pp.read_images_gps(tmp_path / "nowhere", ["a.jpg"])
    with pytest.raises(pp.Error, match="bad_geo.txt:2: y: missing"):
        (tmp_path / "bad_geo.txt").write_text("EPSG:32633\na.jpg 1\n")
        pp.read_geo_txt(tmp_path / "bad_geo.txt")
    # ODM's z is optional: "image x y" is a position without height, its z NaN.
    (tmp_path / "flat_geo.txt").write_text("EPSG:32633\na.jpg 1 2\n")
    record = pp.read_geo_txt(tmp_path / "flat_geo.txt").records[0]
    assert not record.has_height and np.isnan(record.position[2])
    inputs.set_positions("EPSG:32633", ["a.jpg", "b.jpg"], [[1.0, 2.0, np.nan], [1.0, 2.0, 3.0]])
    assert [p.has_height for p in inputs.positions] == [False, True]


def dji_jpeg(lon, lat, height, rtk_sigma_enu_m, rtk_flag):
    """The bytes of a JPEG with no picture and DJI's XMP position tags, as a drone writes them."""
    sigma = dict(zip(("RtkStdLon", "RtkStdLat", "RtkStdHgt"), rtk_sigma_enu_m))
    xmp = ('<?xpacket begin="\ufeff" id="W5M0MpCehiHzreSzNTczkc9d"?>'
           '<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">'
           '<rdf:Description rdf:about="" xmlns:drone-dji="http://www.dji.com/drone-dji/1.0/" '
           f'drone-dji:GpsLatitude="{lat:+.10f}" drone-dji:GpsLongitude="{lon:+.10f}" '
           f'drone-dji:AbsoluteAltitude="{height:+.3f}" drone-dji:RtkFlag="{rtk_flag}" '
           + " ".join(f'drone-dji:{k}="{v}"' for k, v in sigma.items()) +
           '/></rdf:RDF></x:xmpmeta><?xpacket end="w"?>').encode()
    app1 = b"http://ns.adobe.com/xap/1.0/\x00" + xmp
    return b"\xff\xd8\xff\xe1" + (len(app1) + 2).to_bytes(2, "big") + app1 + b"\xff\xd9"


def test_image_gps_from_bytes(tmp_path):
    data = dji_jpeg(-45.25, -22.5, 812.5, (0.01, 0.02, 0.03), 50)
    gps = pp.parse_image_gps(data, name="DJI_0001.JPG")
    assert gps.source == "dji_xmp" and gps.rtk_flag == 50
    np.testing.assert_allclose(gps.lon_lat_height, [-45.25, -22.5, 812.5], rtol=0, atol=1e-9)
    np.testing.assert_allclose(gps.rtk_sigma_enu_m, [0.01, 0.02, 0.03], rtol=0, atol=1e-12)
    # The same as the file read from disk.
    (tmp_path / "DJI_0001.JPG").write_bytes(data)
    from_file = pp.read_image_gps(tmp_path / "DJI_0001.JPG")
    assert repr(from_file) == repr(gps)
    with pytest.raises(pp.Error, match="^in_memory.jpg"):
        pp.parse_image_gps(b"hello\n", name="in_memory.jpg")
    with pytest.raises(pp.Error, match="<bytes>"):
        pp.parse_image_gps(data[:4])
    with pytest.raises(TypeError):
        pp.parse_image_gps("not bytes")


def test_a_block_with_control_joined_is_written_by_the_adjusted_model_writer(tmp_path):
    block, truth, checks = georeference_model(tmp_path, num_control_points=5, num_check_points=4)
    model_points, model_marks = block.num_points, block.num_marks
    write_geo_txt(tmp_path / "geo.txt", block.image_names, truth.image_parameters[:, :3], (0.03, 0.03, 0.05))
    inputs = pp.GeoreferenceInputs()
    inputs.set_positions_from_geo_txt(pp.read_geo_txt(tmp_path / "geo.txt"))
    inputs.set_control_from_gcp_list(pp.read_gcp_list(tmp_path / "gcp_list.txt"), check_points=checks)
    geo = pp.prepare_georeference(block, inputs)
    assert (geo.model_points, geo.model_marks) == (model_points, model_marks)
    # With points at a stage, figures: rmse_m per axis and total_m (m); not evaluated yet, none after
    # the adjustment.
    check = geo.check_after_similarity
    assert check["count"] == 4 and check["rmse_m"].shape == (3,), check
    assert check["total_m"] == pytest.approx(np.linalg.norm(check["rmse_m"]))
    assert geo.check_after_adjustment == {"count": 0, "rmse_m": None, "total_m": None}
    assert block.num_points == model_points + 9 and block.num_marks > model_marks
    assert block.point_roles[model_points:].count("check") == 4
    # write_colmap_model writes a block as it is: one with control joined no longer fits the
    # model's ids and keypoints, and it says which writer to use.
    with pytest.raises(pp.Error, match="write_adjusted_colmap_model"):
        pp.write_colmap_model(block, tmp_path / "as_is")
    result = pp.bundle_adjust(block)
    assert result.summary.is_solution_usable()
    pp.write_adjusted_colmap_model(block, tmp_path / "adjusted", result, geo, format="binary")
    assert sorted(p.name for p in (tmp_path / "adjusted").iterdir()) == [
        "cameras.bin", "georeference.json", "images.bin", "points3D.bin"]
    written = pp.read_colmap_model(tmp_path / "adjusted")
    assert written.num_points == model_points and written.point_ids == block.point_ids[:model_points]
    np.testing.assert_allclose(written.point_positions, block.point_positions[:model_points], atol=1e-9)
    with pytest.raises(ValueError, match="binary"):
        pp.write_adjusted_colmap_model(block, tmp_path / "other", result, geo, format="jpeg")


def test_frames_table_positions_take_their_srs_and_refuse_two_crs(scene, tmp_path):
    block, _, measured = scene
    rows = "".join(f"{n},1,{x:.4f},{y:.4f},{z:.4f},0,0,0,0.03,0.03,0.05,{'EPSG:32633' if i else 'WGS84 UTM 33N'}\n"
                   for i, (n, (x, y, z)) in enumerate(zip(block.image_names, measured)))
    header = "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa,AccuracyX,AccuracyY,AccuracyZ,SRS\n"
    (tmp_path / "gnss.csv").write_text(header + rows)
    inputs = pp.GeoreferenceInputs()
    inputs.set_positions_from_frames(pp.read_frames_table(tmp_path / "gnss.csv"), source="gnss.csv")
    # Two spellings of one CRS are one; the positions and accuracies as in the geo.txt.
    assert inputs.positions_crs == "WGS84 UTM 33N" and len(inputs.positions) == 24
    geo = pp.GeoreferenceInputs()
    geo.set_positions_from_geo_txt(pp.read_geo_txt(tmp_path / "geo.txt"))
    for a, b in zip(inputs.positions, geo.positions):
        assert a.image == b.image
        np.testing.assert_allclose(a.position, b.position, atol=1e-9)
        np.testing.assert_allclose(a.accuracy_m, b.accuracy_m)
    # A row in another CRS is refused at its line and field; so is a crs naming another one.
    (tmp_path / "two.csv").write_text(header + rows.replace("EPSG:32633", "EPSG:32632", 1))
    with pytest.raises(pp.Error, match=r"two\.csv:3: SRS: 'EPSG:32632' is another CRS"):
        pp.GeoreferenceInputs().set_positions_from_frames(pp.read_frames_table(tmp_path / "two.csv"),
                                                          source="two.csv")
    with pytest.raises(pp.Error, match=r"gnss\.csv:2: SRS: 'WGS84 UTM 33N' is another CRS than crs=EPSG:32632"):
        pp.GeoreferenceInputs().set_positions_from_frames(pp.read_frames_table(tmp_path / "gnss.csv"),
                                                          crs="EPSG:32632", source="gnss.csv")
