"""Camera calibration from Python against `lasercell calibrate camera` on OpenCV's real sample
chessboard images (bundled): the same detections and the same intrinsics."""

import glob
import json
import os

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def images(source_dir):
    return sorted(glob.glob(os.path.join(source_dir, "datasets/real/opencv_chessboard/left*.jpg")))


@pytest.fixture(scope="module")
def cli_calibration(cli, source_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("camera")
    pattern = os.path.join(source_dir, "datasets/real/opencv_chessboard/left*.jpg")
    cli("calibrate", "camera", "--images", pattern, "--board", "chessboard:9x6:25",
        "--model", "opencv5", "--fix-aspect", "--out", str(out / "left.cameramodel"),
        "--json", str(out / "left.json"), "--quiet")
    with open(out / "left.json", encoding="utf-8") as f:
        return lasercell.CameraModel.load(str(out / "left.cameramodel")), json.load(f)


def test_the_intrinsics_are_the_clis(images, cli_calibration):
    board = lasercell.Board("chessboard:9x6:25")
    assert board.num_corners == 54 and board.corners_mm.shape == (54, 3)
    detections = lasercell.detect_boards(images, board)
    assert len(detections.views) == len(images) == 13
    assert (detections.width, detections.height) == (640, 480)
    result = lasercell.calibrate_intrinsics(detections.views, board, detections.width,
                                            detections.height, model="opencv5", fix_aspect=True)
    assert result.converged and result.rejection_reason() == ""
    camera, document = cli_calibration
    assert result.camera.lensmodel == camera.lensmodel == "LENSMODEL_OPENCV5"
    np.testing.assert_allclose(result.camera.intrinsics, camera.intrinsics, rtol=1e-12)
    assert result.rms_px == pytest.approx(document["rms_px"], rel=1e-12)
    ours = lasercell.camera_calibration_dict(result, board, detections, model="opencv5",
                                             fix_aspect=True)
    assert ours["format"] == document["format"]
    assert ours["images"] == document["images"]  # per image: detection, corners, pose, rms


def test_own_detections_as_arrays(images):
    board = lasercell.Board("chessboard:9x6:25")
    detections = lasercell.detect_boards(images, board)
    views = [lasercell.BoardView(v.name, np.array(v.corners_px), np.array(v.corner_ids))
             for v in detections.views]
    a = lasercell.calibrate_intrinsics(detections.views, board, 640, 480, model="opencv5")
    b = lasercell.calibrate_intrinsics(views, board, 640, 480, model="opencv5")
    np.testing.assert_array_equal(a.camera.intrinsics, b.camera.intrinsics)


def test_bad_input(images, tmp_path):
    board = lasercell.Board("chessboard:9x6:25")
    with pytest.raises(lasercell.InputError):
        lasercell.Board("chessboard:9x6")
    seen = []
    detections = lasercell.detect_boards(images[:2] + [str(tmp_path / "missing.jpg")], board,
                                         progress=lambda stage, f: seen.append((stage, f)))
    assert seen == [("detect", 1 / 3), ("detect", 2 / 3), ("detect", 1.0)]
    assert len(detections.views) == 2
    path, found, _, message = detections.images[2]
    assert path.endswith("missing.jpg") and not found and message
    with pytest.raises(lasercell.InputError):  # 2 views: too few
        lasercell.calibrate_intrinsics(detections.views, board, 640, 480)
    with pytest.raises(lasercell.InputError, match="model"):
        lasercell.calibrate_intrinsics(detections.views, board, 640, 480, model="fisheye")
    with pytest.raises(lasercell.InputError, match="corner_ids"):
        lasercell.BoardView("x", np.zeros((3, 2)), [0, 1])

    def stop(stage, fraction):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):  # a callback that raises stops the detection
        lasercell.detect_boards(images, board, progress=stop)
