"""lasercell.Job, run_job and JobRunner against `lasercell job run` on the same simulated seat:
the same part and grasp poses in handling_base, the same result file."""

import json

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def cli_result(cli, seat_sim):
    out = str(seat_sim["root"] / "cli_result.json")
    cli("job", "run", seat_sim["job"], "--out", out, "--threads", "1", "--quiet")
    with open(out, encoding="utf-8") as f:
        return json.load(f)


@pytest.fixture(scope="module")
def result(seat_sim):
    return lasercell.run_job(lasercell.Job.load(seat_sim["job"]), threads=1)


def test_the_job_reads_its_files(seat_sim):
    job = lasercell.Job.load(seat_sim["job"])
    assert job.target_frame == "handling_base" and job.grasp_tolerance_mm == 10.0
    assert job.parts == [("seat", 1)]
    assert job.cell == seat_sim["cell"] and job.profiles.endswith("seat_000.lcp")


def test_the_poses_are_the_clis(result, cli_result):
    assert result.all_found and len(result.instances) == 1
    seat = result.instances[0]
    theirs = cli_result["instances"][0]
    assert seat.frame == theirs["frame"] == "seat_1"
    np.testing.assert_allclose(seat.target_from_part, np.array(theirs["matrix"]), atol=1e-9)
    assert set(seat.grasps) == {"hole"}
    assert seat.graspable == theirs["graspable"]
    mine = result.to_dict()
    assert mine["format"] == "lasercell.localization_job"
    assert mine["instances"][0]["handling_base_from_part"] == theirs["handling_base_from_part"]
    assert mine["instances"][0]["grasps"] == theirs["grasps"]


def test_the_seat_is_where_the_simulator_put_it(result, seat_sim):
    truth = lasercell.FrameGraph.load(str(seat_sim["sim"] / "truth/cell.yaml"))
    true_pose = truth.transform("handling_base", "seat_000")
    seat = result.instances[0]
    assert np.linalg.norm(seat.target_from_part[:3, 3] - true_pose[:3, 3]) < 2.0
    assert seat.covariance.shape == (6, 6) and seat.covariance_valid
    cell = lasercell.FrameGraph.load(seat_sim["cell"])
    with_seat = result.cell_with_instances(cell)
    np.testing.assert_allclose(with_seat.transform("handling_base", "seat_1"),
                               seat.target_from_part, atol=1e-9)
    assert result.sweep.frame == "handling_base" and len(result.sweep.cloud) > 10000


def test_a_runner_runs_sweep_after_sweep(seat_sim, result):
    job = lasercell.Job.load(seat_sim["job"])
    stages = []
    runner = lasercell.JobRunner(job, threads=1,
                                 progress=lambda stage, fraction: stages.append(stage))
    profiles = lasercell.read_profiles(job.profiles)
    for _ in range(2):
        again = runner.run(profiles)
        np.testing.assert_allclose(again.instances[0].target_from_part,
                                   result.instances[0].target_from_part, atol=1e-9)
    assert "triangulation" in stages


def test_bad_jobs_name_the_file_and_field(seat_sim, tmp_path):
    bad = tmp_path / "bad.job.yaml"
    bad.write_text("format: lasercell.job\nversion: 1\ncell: cell.yaml\nparts: []\nbogus: 1\n")
    with pytest.raises(lasercell.InputError, match="bad.job.yaml"):
        lasercell.Job.load(str(bad))
    with pytest.raises(lasercell.FileError):
        lasercell.Job.load(str(tmp_path / "missing.job.yaml"))
