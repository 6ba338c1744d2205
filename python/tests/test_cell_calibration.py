"""The laser plane and the half-sphere sensor-to-robot calibration from Python against
`lasercell calibrate laser` and `calibrate spheres` on the same simulated captures, and against
the simulator's truth."""

import json
import re

import numpy as np
import pytest

import lasercell


def record_values(path, key):
    text = path.read_text()
    return [float(v) for v in re.search(rf"^{key}: \[(.*)\]$", text, re.M).group(1).split(",")]


@pytest.fixture(scope="module")
def cli_cell(cli, cell_sim, tmp_path_factory):
    """The CLI's laser plane and spheres, with the true camera, into a fresh cell."""
    out = tmp_path_factory.mktemp("cli_cell")
    camera = str(cell_sim / "truth/camera.cameramodel")
    heights = record_values(cell_sim / "records/planes.yaml", "heights_mm")
    normal = record_values(cell_sim / "records/planes.yaml", "plate_normal_in_sensor")
    cli("calibrate", "laser", "--camera", camera, "--planes", str(cell_sim),
        "--heights-mm", ",".join(repr(h) for h in heights),
        "--plate-normal=" + ",".join(repr(v) for v in normal),
        "--cell", str(out / "cell.yaml"), "--json", str(out / "laser.json"), "--quiet")
    laser_only = lasercell.FrameGraph.load(str(out / "cell.yaml"))
    velocity = record_values(cell_sim / "records/linear_sweep.yaml", "velocity_mm_s_in_sensor")
    t0 = re.search(r"^t0_ns: (\d+)$", (cell_sim / "records/linear_sweep.yaml").read_text(),
                   re.M).group(1)
    cli("calibrate", "spheres", "--cell", str(out / "cell.yaml"), "--camera", camera,
        "--profiles", str(cell_sim / "profiles/spheres.lcp"),
        "--velocity-mm-s=" + ",".join(repr(v) for v in velocity), "--t0-ns", t0,
        "--touches", str(cell_sim / "records/touches.yaml"), "--json", str(out / "spheres.json"))
    with open(out / "laser.json", encoding="utf-8") as f:
        laser = json.load(f)
    with open(out / "spheres.json", encoding="utf-8") as f:
        spheres = json.load(f)
    return {"laser": laser, "spheres": spheres, "laser_only": laser_only,
            "cell": lasercell.FrameGraph.load(str(out / "cell.yaml")),
            "heights": heights, "normal": normal}


@pytest.fixture(scope="module")
def camera(cell_sim):
    return lasercell.CameraModel.load(str(cell_sim / "truth/camera.cameramodel"))


@pytest.fixture(scope="module")
def laser(camera, cell_sim, cli_cell):
    return lasercell.calibrate_laser_plane_from_heights(
        camera, str(cell_sim), cli_cell["heights"], plate_normal=cli_cell["normal"])


def test_the_laser_plane_is_the_clis_and_near_the_truth(laser, cli_cell, cell_sim):
    assert laser.converged and laser.refusal_reason() == ""
    theirs = cli_cell["laser_only"].laser_planes["laser"]
    normal, point = theirs[1], theirs[2]
    np.testing.assert_allclose(laser.plane[:3], normal, atol=1e-12)
    np.testing.assert_allclose(laser.plane[3], -normal @ point, atol=1e-9)
    mine = laser.to_dict()
    assert mine["plane"] == cli_cell["laser"]["plane"]
    for key in ("rms_mm", "points", "normal_sigma_deg", "offset_sigma_mm"):
        assert mine[key] == cli_cell["laser"][key], key
    sensor = (cell_sim / "truth/sensor.yaml").read_text()
    true_normal = np.array(eval(re.search(r"^  normal: (\[.*\])$", sensor, re.M).group(1)))
    angle = np.degrees(np.arccos(min(1.0, abs(laser.plane[:3] @ true_normal))))
    assert angle < 5 * laser.normal_sigma_deg + 0.01  # within the stated uncertainty


def test_the_spheres_edge_is_the_clis_and_near_the_truth(laser, camera, cell_sim, cli_cell):
    cell = lasercell.FrameGraph()
    laser.set_in_cell(cell)
    assert cell.laser_planes["laser"][0] == "sensor"
    result = lasercell.calibrate_spheres(
        cli_cell["laser_only"], camera, lasercell.read_profiles(str(cell_sim / "profiles/spheres.lcp")),
        str(cell_sim / "records/touches.yaml"),
        linear_record=str(cell_sim / "records/linear_sweep.yaml"))
    theirs = cli_cell["cell"].transform("handling_base", "sensor")
    np.testing.assert_allclose(result.handling_base_from_sensor, theirs, atol=1e-9)
    assert result.sensor_modes_propagated
    mine = result.to_dict()
    assert mine["format"] == cli_cell["spheres"]["format"]
    result.set_in_cell(cell)
    np.testing.assert_allclose(cell.transform("handling_base", "sensor"), theirs, atol=1e-9)
    captures = (cell_sim / "truth/captures.yaml").read_text()
    truth = eval(re.search(r"handling_base_from_sensor_at_t0: \{translation_mm: (\[.*?\])",
                           captures).group(1))
    assert np.linalg.norm(result.handling_base_from_sensor[:3, 3] - truth) < 1.0


def test_the_spheres_from_a_cloud_are_the_clis(cli, camera, cell_sim, cli_cell, tmp_path):
    """The sweep triangulated first (scan_profiles through the cell's plane), then the spheres
    fitted in that cloud, as `calibrate spheres --sweep` does with the cloud's file."""
    profiles = lasercell.read_profiles(str(cell_sim / "profiles/spheres.lcp"))
    sweep = lasercell.scan_profiles(profiles, camera, cell=cli_cell["laser_only"],
                                    motion="linear",
                                    linear_record=str(cell_sim / "records/linear_sweep.yaml"))
    cloud_path = str(tmp_path / "spheres.ply")
    lasercell.write_point_cloud(cloud_path, sweep.cloud)
    cloud = lasercell.read_point_cloud(cloud_path)
    touches = str(cell_sim / "records/touches.yaml")
    result = lasercell.calibrate_spheres(cli_cell["laser_only"], cloud=cloud, touches=touches)
    assert not result.sensor_modes_propagated  # a cloud carries no error modes
    cell_path = str(tmp_path / "cell.yaml")
    cli_cell["laser_only"].save(cell_path)
    cli("calibrate", "spheres", "--cell", cell_path, "--sweep", cloud_path, "--touches", touches)
    theirs = lasercell.FrameGraph.load(cell_path).transform("handling_base", "sensor")
    np.testing.assert_allclose(result.handling_base_from_sensor, theirs, atol=1e-9)
    # The same points as the profile variant: the same edge up to the cloud file's rounding.
    np.testing.assert_allclose(result.handling_base_from_sensor[:3, 3],
                               cli_cell["cell"].transform("handling_base", "sensor")[:3, 3],
                               atol=0.01)
    with pytest.raises(lasercell.InputError, match="one of them"):
        lasercell.calibrate_spheres(cli_cell["laser_only"], camera, profiles, touches,
                                    linear_record=str(cell_sim / "records/linear_sweep.yaml"),
                                    cloud=cloud)
    with pytest.raises(lasercell.InputError, match="touches"):
        lasercell.calibrate_spheres(cli_cell["laser_only"], cloud=cloud)


def test_bad_input(camera, cell_sim, laser, tmp_path):
    with pytest.raises(lasercell.InputError):  # one height per file
        lasercell.calibrate_laser_plane_from_heights(camera, str(cell_sim), [150.0, 250.0])
    with pytest.raises(lasercell.FileError):
        lasercell.calibrate_laser_plane_from_heights(camera, str(tmp_path), [1.0, 2.0, 3.0])
    with pytest.raises(lasercell.InputError, match="velocity_mm_s"):
        lasercell.calibrate_spheres(lasercell.FrameGraph(), camera,
                                    lasercell.read_profiles(str(cell_sim / "profiles/spheres.lcp")),
                                    str(cell_sim / "records/touches.yaml"))
    with pytest.raises(lasercell.InputError):  # a cell without a laser plane
        lasercell.calibrate_spheres(lasercell.FrameGraph(), camera,
                                    lasercell.read_profiles(str(cell_sim / "profiles/spheres.lcp")),
                                    str(cell_sim / "records/touches.yaml"),
                                    linear_record=str(cell_sim / "records/linear_sweep.yaml"))
