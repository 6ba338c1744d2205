"""lasercell.FrameGraph against `lasercell frames get` on the demo cell."""

import re

import numpy as np
import pytest

import lasercell

JOINTS = [0.1, -1.2, 1.3, 0.2, 0.5, -0.3]


def cli_matrix(cli, cell, to, from_, joints=None):
    args = ["frames", "get", cell, "--to", to, "--from", from_, "--matrix"]
    if joints:
        args += ["--joints", "vision_robot=" + ",".join(repr(j) for j in joints)]
    rows = re.findall(r"^\s*\[(.*)\]$", cli(*args), re.M)
    return np.array([[float(v) for v in row.split(",")] for row in rows])


def test_frames_and_robots(demo_cell):
    cell = lasercell.FrameGraph.load(demo_cell)
    assert cell.frames == ["camera", "cell", "handling_base", "sensor", "vision_base",
                           "vision_flange"]
    assert cell.robots == ["vision_robot"]
    assert cell.connected("camera", "handling_base")


@pytest.mark.parametrize("to, from_, joints", [
    ("cell", "handling_base", None),
    ("camera", "handling_base", JOINTS),
    ("handling_base", "sensor", JOINTS),
])
def test_transforms_match_the_cli(cli, demo_cell, to, from_, joints):
    cell = lasercell.FrameGraph.load(demo_cell)
    ours = cell.transform(to, from_, {"vision_robot": joints} if joints else None)
    # The CLI prints the shortest text that reads back to the same double.
    np.testing.assert_array_equal(ours, cli_matrix(cli, demo_cell, to, from_, joints))
    back = cell.transform(from_, to, {"vision_robot": np.array(joints)} if joints else None)
    np.testing.assert_allclose(ours @ back, np.eye(4), atol=1e-9)


def test_covariance_and_what_it_leaves_out(demo_cell):
    cell = lasercell.FrameGraph.load(demo_cell)
    flange = cell.transform_with_covariance("vision_flange", "sensor")
    assert flange.complete and flange.covariance.shape == (6, 6)
    np.testing.assert_allclose(np.diag(flange.covariance), [1e-8] * 3 + [0.0025] * 3, rtol=1e-9)
    through_robot = cell.transform_with_covariance("handling_base", "sensor",
                                                   {"vision_robot": JOINTS})
    assert through_robot.crosses_dynamic_edge and not through_robot.complete
    assert through_robot.robots_on_path == ["vision_robot"]
    assert "vision_robot" in through_robot.summary()


def test_save_and_load_round_trip(tmp_path, demo_cell):
    cell = lasercell.FrameGraph.load(demo_cell)
    path = str(tmp_path / "cell.yaml")
    cell.save(path)
    again = lasercell.FrameGraph.load(path)
    assert again.to_yaml() == cell.to_yaml()
    assert lasercell.FrameGraph.from_yaml(cell.to_yaml()).frames == cell.frames


def test_bad_requests_raise_with_the_reason(tmp_path, demo_cell):
    cell = lasercell.FrameGraph.load(demo_cell)
    with pytest.raises(lasercell.InputError, match="joint"):
        cell.transform("handling_base", "sensor")  # robot edge without joint values
    with pytest.raises(lasercell.InputError, match="nowhere"):
        cell.transform("nowhere", "cell")
    with pytest.raises(TypeError, match="joints"):
        cell.transform("handling_base", "sensor", [0.0] * 6)
    with pytest.raises(lasercell.InputError, match=r"joints\['vision_robot'\]"):
        cell.transform("handling_base", "sensor", {"vision_robot": [0.0, np.nan, 0, 0, 0, 0]})
    bad = tmp_path / "cell.yaml"
    bad.write_text("format: lasercell.cell\nversion: 99\n")
    with pytest.raises(lasercell.FileError) as raised:
        lasercell.FrameGraph.load(str(bad))
    assert raised.value.path == str(bad)


def test_a_non_rigid_matrix_is_refused():
    cloud = lasercell.PointCloud(np.eye(3) * 100)
    shear = np.eye(4)
    shear[0, 1] = 0.1
    with pytest.raises(lasercell.InputError, match="not a rotation"):
        cloud.transformed(shear)
    with pytest.raises(lasercell.InputError, match="4x4"):
        cloud.transformed(np.eye(3))


def dh_standard(a, alpha, d, theta):
    """Denavit-Hartenberg (standard): A = Rz(theta) Tz(d) Tx(a) Rx(alpha)."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st],
                     [0, sa, ca, d], [0, 0, 0, 1]])


def test_a_dh_robot_from_python_moves_as_its_table_says(tmp_path, demo_cell):
    dh = np.array([[0.0, np.pi / 2, 89.2, 0.0], [-425.0, 0.0, 0.0, 0.0],
                   [-392.0, 0.0, 0.0, 0.0], [0.0, np.pi / 2, 109.3, 0.0],
                   [0.0, -np.pi / 2, 94.75, 0.0], [0.0, 0.0, 82.5, 0.0]])
    mount = np.eye(4)
    mount[:3, 3] = [10.0, -5.0, 400.0]
    cell = lasercell.FrameGraph()
    cell.set_dh_robot("arm", "arm_base", "arm_flange", dh, base_from_chain=mount)
    expected = mount.copy()
    for row, q in zip(dh, JOINTS):
        expected = expected @ dh_standard(row[0], row[1], row[2], row[3] + q)
    got = cell.transform("arm_base", "arm_flange", joints={"arm": JOINTS})
    np.testing.assert_allclose(got, expected, atol=1e-9)
    path = str(tmp_path / "cell.yaml")
    cell.save(path)
    back = lasercell.FrameGraph.load(path)
    table = back.robot_dh("arm")
    assert table["convention"] == "standard"
    np.testing.assert_allclose(table["dh"][:, :4], dh, atol=1e-12)
    np.testing.assert_allclose(table["base_from_chain"], mount, atol=1e-12)
    np.testing.assert_allclose(back.transform("arm_base", "arm_flange", joints={"arm": JOINTS}),
                               expected, atol=1e-9)
    # The demo cell's robot copied through its table moves the same.
    demo = lasercell.FrameGraph.load(demo_cell)
    table = demo.robot_dh("vision_robot")
    copy = lasercell.FrameGraph()
    copy.set_dh_robot("vision_robot", "vision_base", "vision_flange", table["dh"],
                      table["convention"], table["base_from_chain"], table["chain_from_flange"])
    joints = {"vision_robot": JOINTS}
    np.testing.assert_allclose(copy.transform("vision_base", "vision_flange", joints=joints),
                               demo.transform("vision_base", "vision_flange", joints=joints),
                               atol=1e-9)


def test_bad_robots_are_refused(demo_cell):
    cell = lasercell.FrameGraph.load(demo_cell)
    with pytest.raises(lasercell.InputError, match="dh"):
        cell.set_dh_robot("arm", "a_base", "a_flange", np.zeros((3, 3)))
    with pytest.raises(lasercell.InputError, match="convention"):
        cell.set_dh_robot("arm", "a_base", "a_flange", np.zeros((3, 4)), convention="craig")
    with pytest.raises(lasercell.InputError, match="dh"):
        cell.set_dh_robot("arm", "a_base", "a_flange", np.full((3, 4), np.nan))
    with pytest.raises(lasercell.InputError):  # vision_base and camera are already joined
        cell.set_dh_robot("arm", "vision_base", "camera", np.zeros((3, 4)))
    assert cell.robots == ["vision_robot"]  # unchanged by the refused calls
    with pytest.raises(lasercell.InputError, match="nobody"):
        cell.robot_dh("nobody")
