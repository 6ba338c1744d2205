"""lasercell.PointCloud and the PLY/PCD reader and writer, against the CLI on the same files."""

import re

import numpy as np
import pytest

import lasercell


def cli_info(cli, path):
    """`lasercell cloud info` as numbers: point count and bounding box."""
    text = cli("cloud", "info", path)
    count = int(re.search(r"^points: (\d+)$", text, re.M).group(1))
    box = [
        np.array([float(v) for v in re.search(rf"^bounding box {which}: \[(.*)\]$", text, re.M)
                  .group(1).split(",")])
        for which in ("min", "max")
    ]
    return count, box


def test_read_matches_the_cli(cli, uwa_model):
    cloud = lasercell.read_point_cloud(uwa_model)
    count, (low, high) = cli_info(cli, uwa_model)
    assert len(cloud) == count == 6700
    assert cloud.positions.shape == (6700, 3) and cloud.positions.dtype == np.float64
    # The CLI prints 4 decimals.
    np.testing.assert_allclose(cloud.positions.min(axis=0), low, atol=5e-5)
    np.testing.assert_allclose(cloud.positions.max(axis=0), high, atol=5e-5)
    assert cloud.normals.shape == (6700, 3)
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1.0, atol=1e-6)
    assert cloud.intensity is None and cloud.grid is None and not cloud.is_organized
    assert cloud.field_names == "x y z nx ny nz"


def test_report_says_what_was_read(uwa_model):
    cloud, report = lasercell.read_point_cloud_with_report(uwa_model)
    assert report.format == "ply binary_little_endian"
    assert report.points_in_file == len(cloud) and report.faces == 9140
    assert report.unit_hint == ""


def test_arrays_are_read_only_views_that_keep_the_cloud_alive(uwa_model):
    cloud = lasercell.read_point_cloud(uwa_model)
    positions = cloud.positions
    assert not positions.flags.writeable and positions.flags.c_contiguous
    assert np.shares_memory(positions, cloud.positions)  # no copy per access
    with pytest.raises(ValueError):
        positions[0, 0] = 1.0
    first = positions[0].copy()
    del cloud
    np.testing.assert_array_equal(positions[0], first)  # the view holds the C++ cloud


@pytest.mark.parametrize("extension", ["ply", "pcd"])
def test_every_attribute_survives_a_write_and_a_read(tmp_path, extension):
    rng = np.random.default_rng(7)
    rows, cols = 20, 30
    profile, column = np.divmod(np.arange(rows * cols), cols)
    keep = rng.random(rows * cols) > 0.1  # holes in the grid
    n = int(keep.sum())
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    cloud = lasercell.PointCloud(
        positions=rng.uniform(-200, 200, size=(n, 3)), normals=normals,
        intensity=rng.uniform(0, 255, size=n).astype(np.float32), profile=profile[keep],
        column=column[keep], timestamp_s=np.linspace(0.0, 1.0, n), grid=(rows, cols))
    assert cloud.is_organized
    path = str(tmp_path / f"cloud.{extension}")
    lasercell.write_point_cloud(path, cloud, positions_as_double=True)
    back = lasercell.read_point_cloud(path)
    assert back.grid == (rows, cols)
    np.testing.assert_array_equal(back.positions, cloud.positions)
    np.testing.assert_allclose(back.normals, cloud.normals, atol=1e-7)  # stored as float32
    np.testing.assert_array_equal(back.intensity, cloud.intensity)
    np.testing.assert_array_equal(back.profile, profile[keep])
    np.testing.assert_array_equal(back.column, column[keep])
    np.testing.assert_array_equal(back.timestamp_s, cloud.timestamp_s)


def test_any_real_dtype_and_memory_order_is_copied_in():
    grid = np.arange(30, dtype=np.float32).reshape(10, 3) * 25.0
    fortran = np.asfortranarray(grid)
    strided = np.arange(60, dtype=np.int64).reshape(10, 6)[:, ::2] * 25
    for positions in (grid, fortran, strided, grid.tolist()):
        cloud = lasercell.PointCloud(positions)
        np.testing.assert_array_equal(cloud.positions, np.asarray(positions, dtype=np.float64))


def test_transformed_applies_a_rigid_transform(uwa_model):
    cloud = lasercell.read_point_cloud(uwa_model)
    c, s = np.cos(0.3), np.sin(0.3)
    pose = np.array([[c, -s, 0, 10], [s, c, 0, -5], [0, 0, 1, 2], [0, 0, 0, 1.0]])
    moved = cloud.transformed(pose)
    np.testing.assert_allclose(moved.positions, cloud.positions @ pose[:3, :3].T + pose[:3, 3],
                               atol=1e-9)
    np.testing.assert_allclose(moved.normals, cloud.normals @ pose[:3, :3].T, atol=1e-12)


@pytest.mark.parametrize("positions, error, words", [
    (np.zeros((5, 2)), lasercell.InputError, ["positions", "(N, 3)", "(5, 2)"]),
    (np.zeros(3), lasercell.InputError, ["positions", "(N, 3)", "(3,)"]),
    (np.array([[0, 0, 0], [np.nan, 0, 0]]) * 100, lasercell.InputError, ["positions", "index 1"]),
    (np.zeros((4, 3), dtype=np.complex128), TypeError, ["positions", "complex"]),
    (np.array([["a", "b", "c"]]), TypeError, ["positions", "dtype"]),
])
def test_bad_arrays_raise_naming_the_argument(positions, error, words):
    with pytest.raises(error) as raised:
        lasercell.PointCloud(positions)
    for word in words:
        assert word in str(raised.value)


def test_bad_attributes_name_their_argument():
    positions = np.arange(12, dtype=float).reshape(4, 3) * 50
    with pytest.raises(lasercell.InputError, match="normals: expected 4 rows"):
        lasercell.PointCloud(positions, normals=np.ones((3, 3)))
    with pytest.raises(lasercell.InputError, match="intensity: expected 4 values"):
        lasercell.PointCloud(positions, intensity=np.ones(5))
    with pytest.raises(TypeError, match="profile: expected an integer dtype"):
        lasercell.PointCloud(positions, profile=np.ones(4))
    with pytest.raises(lasercell.InputError, match="grid"):
        lasercell.PointCloud(positions, profile=np.zeros(4, int), column=np.arange(4), grid=(0, 4))
    with pytest.raises(lasercell.InputError, match="PointCloud"):  # grid index outside the grid
        lasercell.PointCloud(positions, profile=np.zeros(4, int), column=np.arange(4), grid=(1, 2))


def test_metres_are_refused_unless_allowed():
    metres = np.random.default_rng(1).uniform(-0.2, 0.2, size=(100, 3))
    with pytest.raises(lasercell.UnitError, match="looks like metres") as raised:
        lasercell.PointCloud(metres)
    assert isinstance(raised.value, lasercell.InputError)
    assert isinstance(raised.value, ValueError)
    assert len(lasercell.PointCloud(metres, allow_small_extent=True)) == 100
    assert len(lasercell.PointCloud(metres * 1000.0)) == 100


def test_file_errors_are_os_errors_with_the_path(tmp_path):
    missing = str(tmp_path / "missing.ply")
    with pytest.raises(lasercell.FileError) as raised:
        lasercell.read_point_cloud(missing)
    assert isinstance(raised.value, OSError) and isinstance(raised.value, lasercell.InputError)
    assert raised.value.path == missing and missing in str(raised.value)
    with pytest.raises(lasercell.FileError, match="unsupported extension"):
        lasercell.read_point_cloud(str(tmp_path / "cloud.xyz"))
    cloud = lasercell.PointCloud(np.eye(3) * 100)
    with pytest.raises(lasercell.InputError, match="ply_encoding"):
        lasercell.write_point_cloud(str(tmp_path / "c.ply"), cloud, ply_encoding="utf8")
