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


def cube(half=10.0):
    """An axis-aligned cube, 8 corners and 12 triangles wound counter-clockwise from outside."""
    corners = np.array([[x, y, z] for x in (-half, half) for y in (-half, half)
                        for z in (-half, half)])
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            on = [i for i, c in enumerate(corners) if c[axis] * sign > 0]
            a, b = [(axis + 1) % 3, (axis + 2) % 3]
            centre = corners[on].mean(axis=0)
            ring = sorted(on, key=lambda i: np.arctan2(corners[i][b] - centre[b],
                                                       corners[i][a] - centre[a]))
            if sign < 0:
                ring = ring[::-1]
            faces += [[ring[0], ring[1], ring[2]], [ring[0], ring[2], ring[3]]]
    return corners, np.array(faces)


def test_a_mesh_from_arrays_writes_and_reads_back(tmp_path):
    corners, faces = cube()
    mesh = lasercell.TriangleMesh(corners, faces)
    for name in ("cube.stl", "cube.ply"):
        lasercell.write_mesh(str(tmp_path / name), mesh)
        back = lasercell.read_mesh(str(tmp_path / name))
        triangles = np.sort(back.vertices.positions[back.faces].reshape(-1, 3), axis=0)
        np.testing.assert_array_equal(triangles,
                                      np.sort(corners[faces].reshape(-1, 3), axis=0))
    with pytest.raises(lasercell.FileError, match="cube.obj"):
        lasercell.write_mesh(str(tmp_path / "cube.obj"), mesh)
    with pytest.raises(lasercell.InputError, match="faces: row 0 names vertex 8"):
        lasercell.TriangleMesh(corners, np.array([[0, 1, 8]]))
    with pytest.raises(lasercell.InputError, match="faces"):
        lasercell.TriangleMesh(corners, np.array([0, 1, 2]))
    with pytest.raises(TypeError, match="integer"):
        lasercell.TriangleMesh(corners, faces.astype(float))


def test_vertex_normals_are_the_area_weighted_face_normals():
    corners, faces = cube()
    extra = np.vstack([corners, [[0.0, 0.0, 100.0]]])  # a vertex no face uses
    mesh = lasercell.TriangleMesh(extra, faces)
    # NumPy: sum of the face normals (cross product = 2 x area x unit normal) per vertex.
    cross = np.cross(extra[faces[:, 1]] - extra[faces[:, 0]], extra[faces[:, 2]] - extra[faces[:, 0]])
    summed = np.zeros_like(extra)
    for k in range(3):
        np.add.at(summed, faces[:, k], cross)
    expected = summed[:8] / np.linalg.norm(summed[:8], axis=1, keepdims=True)
    normals = lasercell.mesh_vertex_normals(mesh)
    np.testing.assert_allclose(normals[:8], expected, atol=1e-12)
    assert np.all(np.sum(normals[:8] * corners, axis=1) > 0)  # outward
    np.testing.assert_array_equal(normals[8], 0.0)
    cloud, dropped = lasercell.with_mesh_normals(mesh)
    assert dropped == 1 and len(cloud) == 8
    np.testing.assert_allclose(cloud.normals, expected, atol=1e-12)


def test_a_part_file_written_from_python_reads_back(pallet, tmp_path):
    part = lasercell.Part.load(str(pallet / "armrest.part.yaml"))
    grip = np.eye(4)
    grip[:3, 3] = [5.0, -2.0, 12.5]
    grip[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    part.set_grasp("side_grip", grip, "fingers on the side")
    path = tmp_path / "armrest.part.yaml"
    (tmp_path / "armrest.step").write_bytes((pallet / "armrest.step").read_bytes())
    part.save(str(path))
    back = lasercell.Part.load(str(path))
    assert set(back.grasps) == {"post_hole", "side_grip"}
    np.testing.assert_allclose(back.grasps["side_grip"], grip, atol=1e-12)
    np.testing.assert_allclose(back.grasps["post_hole"], part.grasps["post_hole"], atol=1e-12)
    assert back.to_yaml() == part.to_yaml()
    again = lasercell.Part.from_yaml(path.read_text(), str(path))
    assert again.to_yaml() == part.to_yaml()
    with pytest.raises(lasercell.InputError, match="Bad Name"):
        part.set_grasp("Bad Name", grip)
    assert set(part.grasps) == {"post_hole", "side_grip"}  # unchanged by the refused call
    with pytest.raises(lasercell.InputError, match="part_from_grasp"):
        part.set_grasp("skewed", np.diag([2.0, 1.0, 1.0, 1.0]))
