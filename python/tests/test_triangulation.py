"""lasercell.read_profiles and lasercell.scan_profiles against `lasercell scan triangulate` on
the same simulated seat sweep: the same points, attributes and grid."""

import re

import numpy as np
import pytest

import lasercell


def linear_record(sim):
    text = (sim / "records/linear_sweep.yaml").read_text()
    velocity = re.search(r"^velocity_mm_s_in_sensor: \[(.*)\]$", text, re.M).group(1)
    t0 = int(re.search(r"^t0_ns: (\d+)$", text, re.M).group(1))
    return [float(v) for v in velocity.split(",")], t0


def test_profiles_as_arrays(seat_sim):
    profiles = lasercell.read_profiles(str(seat_sim["sim"] / "profiles/seat_000.lcp"))
    p, c = len(profiles), profiles.columns
    assert p > 100 and c == profiles.image_width == 1024
    assert profiles.row_px.shape == (p, c) and profiles.row_px.dtype == np.float32
    assert profiles.intensity.shape == profiles.width_px.shape == (p, c)
    assert profiles.sequence.dtype == np.uint64 and profiles.timestamp_ns.dtype == np.int64
    assert np.all(np.diff(profiles.timestamp_ns) > 0)
    assert profiles.joints_rad.shape == (p, 0)
    peaks = ~np.isnan(profiles.row_px)
    assert peaks.any() and np.all(profiles.intensity[~peaks] == 0)


def test_the_sweep_is_the_clis(cli, seat_sim, tmp_path):
    sim = seat_sim["sim"]
    velocity, t0 = linear_record(sim)
    out = str(tmp_path / "sweep.ply")
    cli("scan", "triangulate", "--camera", str(sim / "truth/camera.cameramodel"),
        "--profiles", str(sim / "profiles/seat_000.lcp"),
        "--sensor-truth", str(sim / "truth/sensor.yaml"),
        "--velocity-mm-s=" + ",".join(repr(v) for v in velocity), "--t0-ns", str(t0),
        "--out", out, "--quiet")
    theirs = lasercell.read_point_cloud(out)

    profiles = lasercell.read_profiles(str(sim / "profiles/seat_000.lcp"))
    camera = lasercell.CameraModel.load(str(sim / "truth/camera.cameramodel"))
    sweep = lasercell.scan_profiles(profiles, camera, laser_plane=seat_sim["plane"],
                                    linear_record=str(sim / "records/linear_sweep.yaml"))
    ours = sweep.cloud
    assert sweep.frame == "sensor" and sweep.profiles == len(profiles)
    assert len(ours) == len(theirs) == sweep.counts["points"]
    # The CLI writes float32 positions: equal to float32 rounding (a few um at 1 m).
    np.testing.assert_allclose(ours.positions, theirs.positions, rtol=0, atol=1e-3)
    np.testing.assert_array_equal(ours.profile, theirs.profile)
    np.testing.assert_array_equal(ours.column, theirs.column)
    assert ours.grid == (len(profiles), profiles.columns) and ours.is_organized
    assert sweep.frame_from_sensor.shape == (len(profiles), 4, 4)
    # The sensor moves along the recorded velocity: profile k sits at velocity * t_k.
    t = (profiles.timestamp_ns - t0) * 1e-9
    np.testing.assert_allclose(sweep.frame_from_sensor[:, :3, 3], np.outer(t, velocity),
                               atol=1e-9)


def test_the_sweep_in_the_cells_frame(seat_sim):
    sim = seat_sim["sim"]
    profiles = lasercell.read_profiles(str(sim / "profiles/seat_000.lcp"))
    camera = lasercell.CameraModel.load(str(sim / "truth/camera.cameramodel"))
    cell = lasercell.FrameGraph.load(seat_sim["cell"])
    in_sensor = lasercell.scan_profiles(profiles, camera, cell=cell,
                                        linear_record=str(sim / "records/linear_sweep.yaml"))
    in_base = lasercell.scan_profiles(profiles, camera, cell=cell, target_frame="handling_base",
                                      linear_record=str(sim / "records/linear_sweep.yaml"))
    assert in_base.frame == "handling_base"
    moved = in_sensor.cloud.transformed(cell.transform("handling_base", "sensor"))
    np.testing.assert_allclose(in_base.cloud.positions, moved.positions, atol=1e-9)


def test_bad_input_names_the_argument(seat_sim):
    sim = seat_sim["sim"]
    profiles = lasercell.read_profiles(str(sim / "profiles/seat_000.lcp"))
    camera = lasercell.CameraModel.load(str(sim / "truth/camera.cameramodel"))
    with pytest.raises(lasercell.InputError, match="laser_plane: expected 4 values"):
        lasercell.scan_profiles(profiles, camera, laser_plane=[0, 1, 0])
    with pytest.raises(lasercell.InputError, match="motion"):
        lasercell.scan_profiles(profiles, camera, laser_plane=seat_sim["plane"], motion="helix")
    with pytest.raises(lasercell.InputError, match="laser plane"):
        lasercell.scan_profiles(profiles, camera)
    small = lasercell.CameraModel("LENSMODEL_PINHOLE", [500.0, 500.0, 50.0, 50.0], 100, 100)
    with pytest.raises(lasercell.InputError):
        lasercell.scan_profiles(profiles, small, laser_plane=seat_sim["plane"])
    with pytest.raises(lasercell.FileError):
        lasercell.read_profiles(str(sim / "truth/sensor.yaml"))


def test_profiles_from_arrays_round_trip_and_triangulate_the_same(seat_sim, tmp_path):
    sim = seat_sim["sim"]
    read = lasercell.read_profiles(str(sim / "profiles/seat_000.lcp"))
    built = lasercell.ProfileSet(read.row_px, intensity=read.intensity, width_px=read.width_px,
                                 timestamp_ns=read.timestamp_ns, sequence=read.sequence,
                                 image_width=read.image_width, image_height=read.image_height,
                                 first_column=read.first_column, metadata=read.metadata)
    path = str(tmp_path / "copy.lcp")
    lasercell.write_profiles(path, built)
    back = lasercell.read_profiles(path)
    for field in ("row_px", "intensity", "width_px", "timestamp_ns", "sequence"):
        np.testing.assert_array_equal(getattr(back, field), getattr(read, field), err_msg=field)
    # The file's bytes are the simulator's: same header, same records.
    assert open(path, "rb").read() == (sim / "profiles/seat_000.lcp").read_bytes()
    big = lasercell.ProfileSet(np.full((2, 4), np.nan), timestamp_ns=[2**62, 2**62 + 1])
    np.testing.assert_array_equal(big.timestamp_ns, [2**62, 2**62 + 1])  # exact int64
    with pytest.raises(lasercell.InputError, match="intensity"):
        lasercell.ProfileSet(read.row_px, intensity=read.intensity[:, :10])
    with pytest.raises(lasercell.InputError, match="columns"):
        lasercell.ProfileSet(read.row_px, first_column=100)  # 1024 columns from 100 > width
    with pytest.raises(TypeError, match="timestamp_ns"):
        lasercell.ProfileSet(read.row_px, timestamp_ns=np.zeros(len(read)))
