"""The laser eye-in-hand from sphere sections in Python against `lasercell calibrate
handeye-laser --profiles` on the real AT C5 / Fanuc set (15 profiles of a 40 mm sphere): the
same result document and cell edge from files, the same result again from arrays, and the
errors a user meets with foreign files."""

import json
import os
import re

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def sphere_set(shared_data):
    root = shared_data("laser_robot_sphere")
    return {"profiles": [os.path.join(root, f"p{i}.yml") for i in range(1, 16)],
            "poses": os.path.join(root, "RobPoses.rob")}


@pytest.fixture(scope="module")
def cli_run(cli, sphere_set, source_dir, tmp_path_factory):
    root = tmp_path_factory.mktemp("sections")
    out, cell = str(root / "r.json"), str(root / "cell.yaml")
    cli("calibrate", "handeye-laser", "--profiles", *sphere_set["profiles"], "--poses",
        sphere_set["poses"], "--pose-format", "xyzwpr", "--sphere-side", "-y",
        "--sphere-radius", "40", "--cell", os.path.join(source_dir, "datasets/demo/cell.yaml"),
        "--output", cell, "--json", out)
    with open(out, encoding="utf-8") as f:
        return json.load(f), lasercell.FrameGraph.load(cell)


@pytest.fixture(scope="module")
def result(sphere_set):
    return lasercell.calibrate_handeye_sections(sphere_set["profiles"], sphere_set["poses"],
                                                sphere_radius_mm=40.0, sphere_side="-y",
                                                pose_format="xyzwpr")


def without_date(document):
    return {k: v for k, v in document.items() if k != "date"}


def test_the_result_is_the_clis(result, cli_run, source_dir):
    theirs, their_cell = cli_run
    assert without_date(result.to_dict()) == without_date(theirs)
    assert result.sections_used == 15 and result.converged
    assert result.spread_rms_mm <= 0.3  # the source's own calibration: 0.38 mm
    assert np.isfinite(result.loo_rms_mm) and result.loo_rms_mm >= result.spread_rms_mm
    cell = lasercell.FrameGraph.load(os.path.join(source_dir, "datasets/demo/cell.yaml"))
    result.set_in_cell(cell)
    np.testing.assert_allclose(cell.transform("vision_flange", "sensor"),
                               their_cell.transform("vision_flange", "sensor"), atol=1e-9)
    np.testing.assert_allclose(cell.transform("vision_flange", "sensor"),
                               result.flange_from_sensor, atol=1e-9)


def test_arrays_give_the_same_result(result, sphere_set):
    profiles = [lasercell.read_scan_line_profile(p) for p in sphere_set["profiles"]]
    poses = lasercell.read_robot_poses(sphere_set["poses"], "xyzwpr")
    assert len(poses) == 15 and all(p.missing < p.columns for p in profiles)
    np.testing.assert_array_equal(profiles[0].points[:, 1], 0.0)
    again = lasercell.calibrate_handeye_sections([p.points for p in profiles], poses,
                                                 sphere_radius_mm=40.0, sphere_side="-y")
    np.testing.assert_allclose(again.flange_from_sensor, result.flange_from_sensor, atol=1e-12)
    assert again.spread_rms_mm == pytest.approx(result.spread_rms_mm, abs=1e-12)


def test_the_fanuc_convention_is_what_the_pose_file_says(sphere_set):
    with open(sphere_set["poses"], encoding="utf-8") as f:
        x, y, z, w, p, r = json.load(f)["RobPoses"][0]
    w, p, r = np.radians([w, p, r])
    rz = np.array([[np.cos(r), -np.sin(r), 0], [np.sin(r), np.cos(r), 0], [0, 0, 1]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rx = np.array([[1, 0, 0], [0, np.cos(w), -np.sin(w)], [0, np.sin(w), np.cos(w)]])
    pose = lasercell.read_robot_poses(sphere_set["poses"], "xyzwpr")[0]
    np.testing.assert_allclose(pose[:3, :3], rz @ ry @ rx, atol=1e-12)
    np.testing.assert_allclose(pose[:3, 3], [x, y, z], atol=1e-12)


def test_what_users_get_wrong(sphere_set, tmp_path):
    profiles, poses = sphere_set["profiles"], sphere_set["poses"]
    with pytest.raises(lasercell.InputError, match="pose_format"):
        lasercell.calibrate_handeye_sections(profiles, poses, 40.0, "-y")
    with pytest.raises(lasercell.InputError, match="sphere_side"):
        lasercell.calibrate_handeye_sections(profiles, poses, 40.0, "up", pose_format="xyzwpr")
    with pytest.raises(lasercell.OptionError, match="14 profiles but 15 poses"):
        lasercell.calibrate_handeye_sections(profiles[:14], poses, 40.0, "-y",
                                             pose_format="xyzwpr")
    with pytest.raises(lasercell.Error, match="does not state its Euler convention"):
        lasercell.read_robot_poses(poses)
    with pytest.raises(lasercell.FileError, match=re.escape(poses)):
        lasercell.read_scan_line_profile(poses)
    nan_run = tmp_path / "nan.yml"
    nan_run.write_text("%YAML:1.0\n---\nscan_line: [ .Nan, 0., .Nan, .Nan, 0., .Nan ]\n")
    with pytest.raises(lasercell.FileError, match="nan.yml"):
        lasercell.read_scan_line_profile(str(nan_run))
    points = lasercell.read_scan_line_profile(profiles[0]).points
    with pytest.raises(lasercell.InputError, match="poses"):
        lasercell.calibrate_handeye_sections([points, points], [np.eye(4)], 40.0, "-y")
    with pytest.raises(lasercell.InputError, match="3 of 3 profiles give a usable sphere section"):
        lasercell.calibrate_handeye_sections([points] * 3, [np.eye(4)] * 3, 40.0, "-y")
    with pytest.raises(lasercell.InputError, match="do not determine the hand-eye"):
        lasercell.calibrate_handeye_sections([points] * 6, [np.eye(4)] * 6, 40.0, "-y")
