#!/usr/bin/env python3
"""Calibrate the simulated cell and localize a chair seat in it, from Python.

The chain of the paper's cell (Skotheim et al. 2012), step by step like a notebook:
  1. camera intrinsics from chessboard images,
  2. the laser plane from a white plate swept at three known heights,
  3. the sensor in the handling-robot base from four half spheres touched by the robot,
  4. a seat sweep -> the seat's pose and its hole grasp in the handling-robot base (a job),
and a plot of the sweep, the posed CAD model and the grasp (matplotlib).

Usage (from the repository, after scripts/build):
  PYTHONPATH=build/python python3 examples/python/calibrate_and_localize.py --out /tmp/cellcal
It simulates the captures with `lasercell simulate cell` unless --sim names a folder that holds
them. Units: mm, rad.
"""

import argparse
import glob
import os
import re
import subprocess

import matplotlib

matplotlib.use("Agg")  # files, no window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import lasercell  # noqa: E402


def record(path, key):
    """A number list `key: [a, b, c]` of a lasercell record file (records/*.yaml)."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    return [float(v) for v in re.search(rf"^{key}: \[(.*)\]$", text, re.M).group(1).split(",")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", required=True, help="Folder for the outputs")
    parser.add_argument("--sim", help="Simulated captures (default: simulate into OUT/sim)")
    parser.add_argument("--cli", default="build/tools/lasercell", help="The lasercell CLI")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    sim = args.sim or os.path.join(args.out, "sim")
    if not args.sim:
        subprocess.run([args.cli, "simulate", "cell", "--seed", "3", "--out", sim, "--quiet"],
                       check=True)

    # 1. Camera intrinsics (OPENCV8, refitted as OPENCV5 if it folds over) from the board images.
    board = lasercell.Board("chessboard:9x6:40")
    detections = lasercell.detect_boards(sorted(glob.glob(f"{sim}/images/chessboard_*.png")),
                                         board)
    intrinsics = lasercell.calibrate_intrinsics(detections.views, board, detections.width,
                                                detections.height, fall_back_to_opencv5=True)
    assert intrinsics.rejection_reason() == "", intrinsics.rejection_reason()
    camera = intrinsics.camera
    camera.save(os.path.join(args.out, "camera.cameramodel"))
    print("1. camera:", intrinsics.summary())

    # 2. Laser plane from the plate at known heights (the cell records them).
    planes = os.path.join(sim, "records/planes.yaml")
    laser = lasercell.calibrate_laser_plane_from_heights(
        camera, sim, record(planes, "heights_mm"),
        plate_normal=record(planes, "plate_normal_in_sensor"))
    cell = lasercell.FrameGraph()
    laser.set_in_cell(cell)
    print("2. laser plane:", laser.summary())

    # 3. Sensor -> handling-robot base from the half spheres and the robot's touches.
    linear = os.path.join(sim, "records/linear_sweep.yaml")
    spheres = lasercell.calibrate_spheres(
        cell, camera, lasercell.read_profiles(os.path.join(sim, "profiles/spheres.lcp")),
        os.path.join(sim, "records/touches.yaml"), linear_record=linear)
    spheres.set_in_cell(cell)
    cell.save(os.path.join(args.out, "cell.yaml"))
    print("3. spheres:", spheres.summary())

    # 4. The job: the seat sweep through the calibrated cell -> seat and hole in handling_base.
    job_path = os.path.join(args.out, "seat.job.yaml")
    with open(job_path, "w", encoding="utf-8") as f:
        f.write("format: lasercell.job\nversion: 1\ncell: cell.yaml\n"
                "camera: camera.cameramodel\n"
                f"source: {{file: {os.path.abspath(sim)}/profiles/seat_000.lcp}}\n"
                f"trajectory: {{linear: {os.path.abspath(linear)}}}\n"
                f"parts: [{{part: {os.path.abspath(sim)}/models/seat.part.yaml}}]\n")
    result = lasercell.run_job(lasercell.Job.load(job_path))
    seat = result.instances[0]
    hole = seat.grasps["hole"][:3, 3]
    sigma = np.sqrt(np.diag(seat.covariance)[3:])
    print("4. job:", result.summary())
    print(f"   hole at {np.round(hole, 2)} mm in handling_base; seat position 1 sigma "
          f"{np.round(sigma, 3)} mm")

    # Against the simulator's truth: where it put the seat, and so the hole.
    truth = lasercell.FrameGraph.load(os.path.join(sim, "truth/cell.yaml"))
    true_part = truth.transform("handling_base", "seat_000")
    part_from_hole = np.linalg.inv(seat.target_from_part) @ seat.grasps["hole"]
    true_hole = (true_part @ part_from_hole)[:3, 3]
    print(f"   hole off the truth by {np.linalg.norm(hole - true_hole):.3f} mm "
          f"(the gripper needs 10)")

    # The plot: the sweep from above, the CAD model at the found pose, the hole grasp.
    points = result.sweep.cloud.positions[::20]
    model = lasercell.read_point_cloud(os.path.join(sim, "models/seat.ply"))
    posed = model.transformed(seat.target_from_part).positions
    fig, ax = plt.subplots(figsize=(8, 6))
    shown = ax.scatter(points[:, 0], points[:, 1], c=points[:, 2], s=0.5, cmap="viridis")
    ax.scatter(posed[:, 0], posed[:, 1], s=0.3, c="tab:red", alpha=0.3, label="CAD at the pose")
    ax.plot(hole[0], hole[1], "k+", markersize=16, label="hole grasp")
    ax.set_xlabel("x, mm (handling_base)")
    ax.set_ylabel("y, mm")
    ax.set_aspect("equal")
    ax.legend(loc="upper right")
    fig.colorbar(shown, label="z, mm")
    ax.set_title("Seat sweep and the localized seat")
    png = os.path.join(args.out, "seat_in_handling_base.png")
    fig.savefig(png, dpi=100)
    print("plot:", png)


if __name__ == "__main__":
    main()
