"""Eye-in-hand from Python against `lasercell calibrate handeye` on the real kuka2 set (28 views
of a 24x17 chessboard, KUKA poses in metres): the same edge, the same result document."""

import glob
import json
import os

import numpy as np
import pytest

import lasercell

BOARD = "chessboard:24x17:15"


@pytest.fixture(scope="module")
def kuka2(shared_data, tmp_path_factory):
    root = shared_data("handeye_kuka2")
    images = sorted(glob.glob(os.path.join(root, "im_*.png")))
    board = lasercell.Board(BOARD)
    detections = lasercell.detect_boards(images, board)
    intrinsics = lasercell.calibrate_intrinsics(detections.views, board, detections.width,
                                                detections.height, model="opencv5")
    camera = str(tmp_path_factory.mktemp("kuka2") / "kuka2.cameramodel")
    intrinsics.camera.save(camera)
    return {"root": root, "images": images, "camera": camera,
            "poses": os.path.join(root, "RobotPosesVec.txt")}


def test_the_edge_is_the_clis(cli, kuka2, tmp_path):
    cell_path, out = str(tmp_path / "cell.yaml"), str(tmp_path / "he.json")
    cli("calibrate", "handeye", "--cell", cell_path, "--camera", kuka2["camera"],
        "--images", os.path.join(kuka2["root"], "im_*.png"), "--board", BOARD,
        "--poses", kuka2["poses"], "--pose-format", "kuka", "--json", out)
    with open(out, encoding="utf-8") as f:
        theirs = json.load(f)
    stages = []
    result = lasercell.calibrate_handeye(kuka2["camera"], kuka2["poses"], images=kuka2["images"],
                                         board=BOARD, pose_format="kuka",
                                         progress=lambda stage, f: stages.append((stage, f)))
    assert stages[0] == ("detect", 1 / 28) and stages[-2:] == [("detect", 1.0), ("solve", 1.0)]
    cell = lasercell.FrameGraph.load(cell_path)
    np.testing.assert_allclose(result.flange_from_camera,
                               cell.transform("vision_flange", "sensor"), atol=1e-9)
    assert len(result.views) == 28
    mine = result.to_dict()
    assert mine["flange_from_camera"] == theirs["flange_from_camera"]
    assert mine["reprojection_rms_px"] == theirs["reprojection_rms_px"]
    assert mine["axxb"]["motions"] == theirs["axxb"]["motions"]
    mine_cell = lasercell.FrameGraph()
    result.set_in_cell(mine_cell)
    assert mine_cell.transform_with_covariance("vision_flange", "sensor").complete


def test_bad_input(kuka2):
    with pytest.raises(lasercell.OptionError, match="images or a corners file"):
        lasercell.calibrate_handeye(kuka2["camera"], kuka2["poses"])
    with pytest.raises(lasercell.OptionError, match="board"):
        lasercell.calibrate_handeye(kuka2["camera"], kuka2["poses"], images=kuka2["images"])
    with pytest.raises(lasercell.InputError):  # 27 images for 28 poses
        lasercell.calibrate_handeye(kuka2["camera"], kuka2["poses"], images=kuka2["images"][:-1],
                                    board=BOARD, pose_format="kuka")
    with pytest.raises(lasercell.OptionError, match="method"):
        lasercell.calibrate_handeye(kuka2["camera"], kuka2["poses"], images=kuka2["images"],
                                    board=BOARD, pose_format="kuka", method="guess")
