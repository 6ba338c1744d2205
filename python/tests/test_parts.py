"""Meshes, CAD files and part files from Python, against `lasercell model info` and the PLY
reader on the simulator's pallet parts (STEP written through OpenCASCADE), and the cluster
filter on a cloud whose components are known by construction."""

import re

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def pallet(cli, tmp_path_factory):
    root = tmp_path_factory.mktemp("pallet")
    cli("simulate", "pallet", "--scenes", "1", "--out", str(root), "--quiet")
    return root / "models"


def test_a_step_part_is_what_model_info_says(cli, pallet):
    info = cli("model", "info", str(pallet / "armrest.part.yaml"))
    cad = lasercell.read_cad_model(str(pallet / "armrest.step"))
    assert cad.format == "step" and cad.source_unit == "mm" and cad.scale_to_mm == 1.0
    samples = int(re.search(r"surface points (\d+)", info).group(1))
    assert len(cad.samples) == samples  # the part file's sampling is the default, 1 mm
    np.testing.assert_allclose(np.linalg.norm(cad.samples.normals, axis=1), 1.0, atol=1e-9)
    assert cad.mesh.faces.shape[1] == 3 and cad.mesh.faces.max() < len(cad.mesh.vertices)
    assert cad.surface_area_mm2 > 0 and cad.solids >= 1
    part = lasercell.Part.load(str(pallet / "armrest.part.yaml"))
    assert part.name == "armrest" and part.model_path.endswith("armrest.step")
    grasp = re.search(r"grasp post_hole: part_from_grasp \{translation_mm: \[(.*?)\]", info)
    np.testing.assert_allclose(part.grasps["post_hole"][:3, 3],
                               [float(v) for v in grasp.group(1).split(",")])
    assert "format: lasercell.part" in part.to_yaml()


def test_meshes_read_the_same_in_every_format(pallet):
    ply = lasercell.read_mesh(str(pallet / "seat.ply"))
    stl = lasercell.read_mesh(str(pallet / "seat.stl"))
    assert len(ply.faces) == len(stl.faces) > 0
    _, report = lasercell.read_point_cloud_with_report(str(pallet / "seat.ply"))
    assert report.faces == len(ply.faces)
    # STL stores float32 corners per triangle: the same triangles up to float32 rounding.
    corners_ply = np.sort(ply.vertices.positions[ply.faces].reshape(-1, 3), axis=0)
    corners_stl = np.sort(stl.vertices.positions[stl.faces].reshape(-1, 3), axis=0)
    np.testing.assert_allclose(corners_ply, corners_stl, atol=1e-3)


def test_bad_files(pallet, tmp_path):
    with pytest.raises(lasercell.InputError, match="STEP"):
        lasercell.read_cad_model(str(pallet / "seat.ply"))
    with pytest.raises(lasercell.FileError):
        lasercell.read_cad_model(str(tmp_path / "missing.step"))
    with pytest.raises(lasercell.OptionError, match="sampling_step_mm"):
        lasercell.read_cad_model(str(pallet / "armrest.step"), sampling_step_mm=0.0)
    with pytest.raises(lasercell.FileError):
        lasercell.read_mesh(str(tmp_path / "missing.stl"))
    with pytest.raises(lasercell.FileError):
        lasercell.Part.load(str(tmp_path / "missing.part.yaml"))


def test_small_clusters_are_removed():
    rng = np.random.default_rng(2)
    big = rng.uniform(0.0, 20.0, (400, 3))      # ~2.7 mm spacing: one component at 8 mm
    small = rng.uniform(0.0, 3.0, (20, 3)) + 500.0  # 20 points far away
    cloud = lasercell.PointCloud(np.vstack([big, small]))
    kept, labels = lasercell.remove_small_clusters(cloud, radius_mm=8.0, min_cluster_size=50)
    np.testing.assert_array_equal(kept, np.arange(400))
    assert len(np.unique(labels[:400])) == 1 and len(np.unique(labels[400:])) == 1
    assert labels[0] != labels[400]
    with pytest.raises(lasercell.OptionError, match="radius_mm"):
        lasercell.remove_small_clusters(cloud, radius_mm=-1.0)
