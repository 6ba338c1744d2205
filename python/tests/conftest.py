"""Shared fixtures: paths to bundled data and a runner for the lasercell CLI, whose output on the
same files is what the bindings are compared with."""

import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def source_dir():
    path = os.environ.get("LASERCELL_SOURCE_DIR")
    if not path:
        pytest.fail("LASERCELL_SOURCE_DIR is not set (ctest sets it; see tests/CMakeLists.txt)")
    return path


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("LASERCELL_CLI")
    if not path:
        pytest.fail("LASERCELL_CLI is not set (ctest sets it; see tests/CMakeLists.txt)")

    def run(*args):
        done = subprocess.run([path, *args], capture_output=True, text=True, check=False)
        assert done.returncode == 0, done.stderr
        return done.stdout

    return run


@pytest.fixture(scope="session")
def uwa_model(source_dir):
    return os.path.join(source_dir, "datasets/real/uwa/parasaurolophus_6700.bin.ply")


@pytest.fixture(scope="session")
def demo_cell(source_dir):
    return os.path.join(source_dir, "datasets/demo/cell.yaml")


@pytest.fixture(scope="session")
def seat_sim(cli, tmp_path_factory):
    """One simulated chair-seat sweep (`lasercell simulate seat`): profiles, camera, linear-axis
    record, part file and the simulator's truth; plus a job-ready cell.yaml built from that truth
    with the bindings (laser plane, handling_base <- sensor at the sweep's t0), as the C++ job
    tests build theirs."""
    import re

    import numpy as np

    import lasercell

    root = tmp_path_factory.mktemp("seat_sim")
    sim = root / "sim"
    cli("simulate", "seat", "--placements", "1", "--seed", "21", "--out", str(sim), "--quiet")
    sensor = (sim / "truth/sensor.yaml").read_text()
    normal = np.array(eval(re.search(r"^  normal: (\[.*\])$", sensor, re.M).group(1)))
    d_mm = float(re.search(r"^  d_mm: (.*)$", sensor, re.M).group(1))
    captures = (sim / "truth/captures.yaml").read_text()
    pose = re.search(r"handling_base_from_sensor_at_t0: \{translation_mm: (\[.*?\]), "
                     r"rotation_wxyz: (\[.*?\])\}", captures)
    translation, (w, x, y, z) = eval(pose.group(1)), eval(pose.group(2))
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    handling_base_from_sensor = np.eye(4)
    handling_base_from_sensor[:3, :3] = rotation
    handling_base_from_sensor[:3, 3] = translation
    cell = lasercell.FrameGraph.load(str(sim / "truth/cell.yaml"))
    cell.remove_edge("vision_flange", "sensor")
    cell.set_static_edge("handling_base", "sensor", handling_base_from_sensor)
    cell.set_laser_plane("laser", normal, -d_mm * normal)
    cell.save(str(root / "cell.yaml"))
    (root / "seat.job.yaml").write_text(
        "format: lasercell.job\nversion: 1\ncell: cell.yaml\n"
        "camera: sim/truth/camera.cameramodel\nsource: {file: sim/profiles/seat_000.lcp}\n"
        "trajectory: {linear: sim/records/linear_sweep.yaml}\n"
        "parts: [{part: sim/models/seat.part.yaml}]\n")
    return {"root": root, "sim": sim, "plane": np.append(normal, d_mm),
            "job": str(root / "seat.job.yaml"), "cell": str(root / "cell.yaml")}


@pytest.fixture(scope="session")
def cell_sim(cli, tmp_path_factory):
    """A simulated calibration capture set of the cell (`lasercell simulate cell`): board images,
    plate and sphere sweeps, touches, the linear-axis record, and the truth."""
    root = tmp_path_factory.mktemp("cell_sim")
    cli("simulate", "cell", "--seed", "3", "--out", str(root / "sim"), "--quiet")
    return root / "sim"


@pytest.fixture(scope="session")
def shared_data(source_dir):
    """A set of the development data (../shared/data, or $LASERCELL_SHARED_DATA) by name. As in
    the C++ tests: skipped when absent, a failure with LASERCELL_REQUIRE_SHARED_DATA=1 (CI)."""
    root = os.environ.get("LASERCELL_SHARED_DATA") or os.path.join(source_dir, "../shared/data")

    def get(name):
        path = os.path.join(root, name)
        if not os.path.isdir(path):
            message = f"shared data set {name} not found under {root}"
            if os.environ.get("LASERCELL_REQUIRE_SHARED_DATA") == "1":
                pytest.fail(message)
            pytest.skip(message)
        return path

    return get
