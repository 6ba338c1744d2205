"""lasercell.CameraModel against mrcal's own Python module (Debian python3-mrcal): projection,
gradients and unprojection agree to 1e-9 px, and the .cameramodel files read both ways."""

import mrcal  # python3-mrcal, installed by scripts/install-deps: missing fails, never skips
import numpy as np
import pytest

import lasercell

SPLINED = "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100"


def models():
    """An OPENCV8 camera like the simulated sensor's and a splined one with a random surface."""
    rng = np.random.default_rng(3)
    opencv8 = [1800.0, 1805.0, 1023.5, 767.2, -0.12, 0.05, 1e-4, -2e-4, 0.01, 0.002, -0.001, 0.003]
    n_spline = mrcal.lensmodel_num_params(SPLINED) - 4
    splined = [900.0, 900.0, 1023.5, 767.5] + list(rng.normal(0.0, 0.02, n_spline))
    return [("LENSMODEL_OPENCV8", opencv8), (SPLINED, splined)]


def points_in_view(rng, n=500):
    p = np.column_stack([rng.uniform(-400, 400, n), rng.uniform(-300, 300, n),
                         rng.uniform(500, 1500, n)])
    return p


@pytest.mark.parametrize("lensmodel,intrinsics", models(), ids=["opencv8", "splined"])
def test_project_and_unproject_agree_with_mrcal(lensmodel, intrinsics):
    camera = lasercell.CameraModel(lensmodel, intrinsics, 2048, 1536)
    rng = np.random.default_rng(11)
    p = points_in_view(rng)
    ours = camera.project(p)
    theirs = mrcal.project(p, lensmodel, np.array(intrinsics))
    assert ours.shape == (len(p), 2)
    assert np.abs(ours - theirs).max() <= 1e-9

    q, dq_dp, dq_di = camera.project(p, gradients=True)
    q2, dq_dp2, dq_di2 = mrcal.project(p, lensmodel, np.array(intrinsics), get_gradients=True)
    assert np.abs(q - q2).max() <= 1e-9
    np.testing.assert_allclose(dq_dp, dq_dp2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(dq_di, dq_di2, rtol=1e-12, atol=1e-9)
    assert dq_di.shape == (len(p), 2, len(intrinsics))

    rays = camera.unproject(ours)
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0, atol=1e-12)
    theirs_rays = mrcal.unproject(ours, lensmodel, np.array(intrinsics), normalize=True)
    assert np.abs(rays - theirs_rays).max() <= 1e-9
    # Back through the projection: the ray's pixel is the pixel.
    assert np.abs(camera.project(rays * 1000.0) - ours).max() <= 1e-6


def test_one_point_in_gives_one_pixel_out():
    lensmodel, intrinsics = models()[0]
    camera = lasercell.CameraModel(lensmodel, intrinsics, 2048, 1536)
    q = camera.project([10.0, -20.0, 800.0])
    assert q.shape == (2,)
    assert camera.unproject(q).shape == (3,)


def test_files_read_both_ways(tmp_path):
    lensmodel, intrinsics = models()[0]
    camera = lasercell.CameraModel(lensmodel, intrinsics, 2048, 1536)
    ours = str(tmp_path / "ours.cameramodel")
    camera.save(ours, comment="written by the Python test")
    model = mrcal.cameramodel(ours)
    assert model.intrinsics()[0] == lensmodel
    np.testing.assert_array_equal(model.intrinsics()[1], intrinsics)  # printed to round-trip
    assert tuple(model.imagersize()) == (2048, 1536)

    theirs = str(tmp_path / "theirs.cameramodel")
    mrcal.cameramodel(intrinsics=(lensmodel, np.array(intrinsics)),
                      imagersize=(2048, 1536)).write(theirs)
    back = lasercell.CameraModel.load(theirs)
    assert back.lensmodel == lensmodel and (back.width, back.height) == (2048, 1536)
    np.testing.assert_array_equal(back.intrinsics, intrinsics)
    assert back.intrinsics_covariance is None
    assert lasercell.CameraModel.from_text(camera.to_text()).lensmodel == lensmodel


def test_bad_input_names_the_argument(tmp_path):
    with pytest.raises(lasercell.InputError, match="LENSMODEL_NOPE"):
        lasercell.CameraModel("LENSMODEL_NOPE", [1, 1, 1, 1], 10, 10)
    with pytest.raises(lasercell.InputError):
        lasercell.CameraModel("LENSMODEL_OPENCV8", [1000.0, 1000.0, 5.0, 5.0], 10, 10)
    camera = lasercell.CameraModel("LENSMODEL_PINHOLE", [1000.0, 1000.0, 5.0, 5.0], 10, 10)
    with pytest.raises(lasercell.InputError, match=r"points: expected shape \(N, 3\)"):
        camera.project(np.zeros((4, 2)))
    with pytest.raises(lasercell.InputError, match="pixels: value at index 1 is NaN"):
        camera.unproject([[1.0, np.nan]])
    with pytest.raises(TypeError, match="points"):
        camera.project(np.array([["a", "b", "c"]]))
    with pytest.raises(lasercell.FileError) as info:
        lasercell.CameraModel.load(str(tmp_path / "missing.cameramodel"))
    assert info.value.path.endswith("missing.cameramodel")
