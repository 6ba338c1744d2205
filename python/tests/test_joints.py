"""Joint offsets and the laser eye-in-hand from Python against `lasercell calibrate joints` and
`calibrate handeye-laser` on the same simulated pose sweeps (a small set, as the C++ CLI test
uses): the same cells and documents."""

import json
import re

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def poses(cli, tmp_path_factory):
    root = tmp_path_factory.mktemp("pose_sweeps")
    (root / "sim.yaml").write_text(
        "format: lasercell.sim_config\nversion: 1\nseed: 5\n"
        "eye_in_hand: {profiles: 12}\njoint_poses: {profiles: 10}\n"
        "captures: {planes: false, spheres: false, seats: false, trajectory: false, "
        "chessboard_images: false, laser_line_images: false, meshes: false}\n")
    cli("simulate", "cell", "--quiet", "--out", str(root / "sim"), "--config",
        str(root / "sim.yaml"))
    sensor = (root / "sim/truth/sensor.yaml").read_text()
    normal = eval(re.search(r"^  normal: (\[.*\])$", sensor, re.M).group(1))
    d_mm = float(re.search(r"^  d_mm: (.*)$", sensor, re.M).group(1))
    # A cell whose vision robot is nominal (joint offsets zeroed): what a user starts from.
    truth = (root / "sim/truth/cell.yaml").read_text()
    (root / "nominal.yaml").write_text(
        re.sub(r"joint_offset_rad: [-0-9.e]+", "joint_offset_rad: 0", truth))
    return {"root": root, "plane": normal + [d_mm], "cell": str(root / "nominal.yaml"),
            "camera": str(root / "sim/truth/camera.cameramodel"),
            "sweeps": str(root / "sim/records/sphere_sweeps.yaml")}


def cli_args(poses, out_cell, out_json):
    return ["--cell", poses["cell"], "--camera", poses["camera"], "--sweeps", poses["sweeps"],
            "--laser-plane=" + ",".join(repr(v) for v in poses["plane"]),
            "--output", out_cell, "--json", out_json]


def test_joints_are_the_clis(cli, poses, tmp_path):
    out_cell, out_json = str(tmp_path / "cell.yaml"), str(tmp_path / "joints.json")
    cli("calibrate", "joints", *cli_args(poses, out_cell, out_json))
    with open(out_json, encoding="utf-8") as f:
        theirs = json.load(f)
    result = lasercell.calibrate_joints(poses["cell"], poses["camera"], poses["sweeps"],
                                        laser_plane=poses["plane"])
    assert result.converged and result.offsets
    assert result.to_dict()["joint_offsets"] == theirs["joint_offsets"]
    assert result.cell.to_yaml() == lasercell.FrameGraph.load(out_cell).to_yaml()


def test_laser_handeye_is_the_clis(cli, poses, tmp_path):
    out_cell, out_json = str(tmp_path / "cell.yaml"), str(tmp_path / "he.json")
    cli("calibrate", "handeye-laser", *cli_args(poses, out_cell, out_json))
    result = lasercell.calibrate_handeye_laser(poses["cell"], poses["camera"], poses["sweeps"],
                                               laser_plane=poses["plane"])
    theirs = lasercell.FrameGraph.load(out_cell)
    np.testing.assert_allclose(result.flange_from_sensor,
                               theirs.transform("vision_flange", "sensor"), atol=1e-9)
    with open(out_json, encoding="utf-8") as f:
        assert result.to_dict() == json.load(f)


def test_bad_input(poses):
    with pytest.raises(lasercell.InputError, match="nope"):
        lasercell.calibrate_joints(poses["cell"], poses["camera"], poses["sweeps"], set="nope",
                                   laser_plane=poses["plane"])
    with pytest.raises(lasercell.InputError, match="laser_plane"):
        lasercell.calibrate_joints(poses["cell"], poses["camera"], poses["sweeps"],
                                   laser_plane=[0, 0, 0, 1])
    with pytest.raises(lasercell.FileError):
        lasercell.calibrate_joints("/nonexistent/cell.yaml", poses["camera"], poses["sweeps"])
