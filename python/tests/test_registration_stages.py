"""The registration stages bound on their own (normals, crop, voxel grid, ICP), checked against
NumPy computations of the same thing on the real UWA clouds."""

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def model_cloud(uwa_model):
    return lasercell.read_point_cloud(uwa_model)


def test_estimated_normals_of_a_sphere_are_radial_and_face_the_viewpoint():
    rng = np.random.default_rng(5)
    direction = rng.normal(size=(5000, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    direction = direction[direction[:, 2] > 0.2]  # the cap a sensor above it sees
    sphere = lasercell.PointCloud(50.0 * direction)
    viewpoint = np.array([0.0, 0.0, 1000.0])
    estimated = lasercell.estimate_normals(sphere, viewpoint_mm=viewpoint, options={"k": 12},
                                           threads=1)
    assert len(estimated) == len(sphere)
    normals = estimated.normals
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-9)
    assert np.all(np.einsum("ij,ij->i", normals, viewpoint - estimated.positions) >= 0.0)
    # A PCA plane through 12 neighbours of a 50 mm sphere sampled every ~2.5 mm: the chord's
    # tilt stays under a degree or two, so every normal is within 5 deg of the radial direction.
    radial = estimated.positions / 50.0
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", normals, radial), -1, 1))).max() < 5


def test_crop_box_is_the_numpy_mask(model_cloud):
    p = model_cloud.positions
    low, high = np.percentile(p, 25, axis=0), np.percentile(p, 75, axis=0)
    cropped = lasercell.crop_box(model_cloud, low, high)
    mask = np.all((p >= low) & (p <= high), axis=1)
    np.testing.assert_array_equal(cropped.positions, p[mask])
    np.testing.assert_array_equal(cropped.normals, model_cloud.normals[mask])
    shift = np.eye(4)
    shift[:3, 3] = [1000.0, 0.0, 0.0]
    assert len(lasercell.crop_box(model_cloud, low, high, frame_from_cloud=shift)) == 0


def test_voxel_grid_keeps_one_point_per_occupied_voxel(model_cloud):
    size = 5.0
    sampled = lasercell.voxel_grid_downsample(model_cloud, size, normal_mode="none")
    p = model_cloud.positions
    voxels = np.unique(np.floor((p - p.min(axis=0)) / size).astype(np.int64), axis=0)
    assert len(sampled) == len(voxels)
    assert sampled.normals is None
    with pytest.raises(lasercell.OptionError, match="voxel_size_mm"):
        lasercell.voxel_grid_downsample(model_cloud, 0.0)
    with pytest.raises(lasercell.InputError, match="normal_mode"):
        lasercell.voxel_grid_downsample(model_cloud, size, normal_mode="median")


def test_icp_undoes_a_known_offset(model_cloud):
    angle = np.radians(3.0)
    offset = np.eye(4)
    offset[:3, :3] = [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0],
                      [0, 0, 1]]
    offset[:3, 3] = [2.0, -1.5, 1.0]
    moved = model_cloud.transformed(offset)  # source = target moved by `offset`
    result = lasercell.align_icp(moved, model_cloud, np.eye(4), options={"max_iterations": 50})
    assert result["converged"], result["summary"]
    # target_from_source undoes the offset: its product with the offset is the identity.
    residual = result["target_from_source"] @ offset
    assert np.abs(residual[:3, 3]).max() < 1e-3
    assert np.abs(residual[:3, :3] - np.eye(3)).max() < 1e-5
    assert result["covariance"].shape == (6, 6)
    with pytest.raises(lasercell.InputError, match="target normals"):
        lasercell.align_icp(moved, lasercell.PointCloud(model_cloud.positions), np.eye(4))
    with pytest.raises(lasercell.InputError, match="initial_target_from_source"):
        lasercell.align_icp(moved, model_cloud, np.eye(3))
