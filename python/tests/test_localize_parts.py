"""lasercell.localize_parts on a cloud the program holds, against the job that triangulated it:
the same seat and grasp poses from the same sweep and part model; load_part_model from the
job's cache; lines_of_sight against the sweep's sensor poses; bad requests."""

import numpy as np
import pytest

import lasercell


@pytest.fixture(scope="module")
def job_run(seat_sim):
    job = lasercell.Job.load(seat_sim["job"])
    runner = lasercell.JobRunner(job, threads=1)
    return runner, runner.run(lasercell.read_profiles(job.profiles))


def test_the_poses_are_the_jobs(job_run):
    runner, result = job_run
    sweep = result.sweep
    stages = []
    mine = lasercell.localize_parts(sweep.cloud, [(runner.models[0], 1)],
                                    line_of_sight=lasercell.lines_of_sight(sweep), threads=1,
                                    progress=lambda stage, fraction: stages.append(stage))
    assert mine.all_found and len(mine.instances) == 1 and len(mine.searches) == 1
    seat, theirs = mine.instances[0], result.instances[0]
    assert seat.frame == theirs.frame == "seat_1"
    np.testing.assert_allclose(seat.target_from_part, theirs.target_from_part, atol=1e-9)
    np.testing.assert_allclose(seat.grasps["hole"], theirs.grasps["hole"], atol=1e-9)
    assert seat.graspable == theirs.graspable
    # This cell's edges carry no covariance (the job notes it), so the job's pose covariance is
    # the fit's alone, which is what localize_parts reports.
    assert any("has no covariance" in note for note in result.notes)
    assert seat.covariance_valid
    np.testing.assert_allclose(seat.covariance, theirs.covariance, rtol=1e-9, atol=1e-15)
    assert mine.sweep_points == len(sweep.cloud) and mine.searches[0].found == 1
    # The search's work, as the job's result file reports it: the same counts (deterministic),
    # every stage timed.
    search, theirs_search = mine.searches[0].to_dict(), result.to_dict()["searches"][0]
    assert search["counts"] == theirs_search["counts"]
    assert search["counts"]["votes_cast"] > search["counts"]["scene_pairs"] > 0
    assert set(search["timings_ms"]) == set(theirs_search["timings_ms"])
    assert {"matching", "judgement", "total"} <= set(search["timings_ms"])
    # An ROI around the seat (a list or a tuple) keeps the same pose and fewer points.
    centre = seat.target_from_part[:3, 3]
    boxed = lasercell.localize_parts(sweep.cloud, [runner.models[0]],
                                     line_of_sight=lasercell.lines_of_sight(sweep), threads=1,
                                     roi=[centre - 400.0, centre + 400.0])
    assert boxed.roi_points < boxed.sweep_points and boxed.all_found
    np.testing.assert_allclose(boxed.instances[0].target_from_part[:3, 3], centre, atol=0.5)
    assert stages and stages[-1].startswith("seat")


def test_the_part_model_loads_from_the_jobs_cache(job_run, seat_sim):
    runner, _ = job_run
    part = lasercell.Part.load(str(seat_sim["sim"] / "models/seat.part.yaml"))
    model = lasercell.load_part_model(part, load_mesh=False)
    assert model.from_cache and model.digest == runner.models[0].digest
    assert model.ppf.pair_count == runner.models[0].ppf.pair_count > 0
    assert model.part.name == "seat" and "seat" in model.summary()


def test_lines_of_sight_point_at_the_sensor_of_each_profile(job_run):
    _, result = job_run
    sweep = result.sweep
    sight = lasercell.lines_of_sight(sweep)
    cloud = sweep.cloud
    assert sight.shape == (len(cloud), 3)
    np.testing.assert_allclose(np.linalg.norm(sight, axis=1), 1.0, atol=1e-12)
    centres = sweep.frame_from_sensor[cloud.profile, :3, 3]
    expected = centres - cloud.positions
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(sight, expected, atol=1e-12)


def test_bad_requests_name_the_argument(job_run):
    runner, result = job_run
    cloud = result.sweep.cloud
    with pytest.raises(lasercell.InputError, match="parts"):
        lasercell.localize_parts(cloud, [])
    with pytest.raises(TypeError, match="PartModel"):
        lasercell.localize_parts(cloud, ["seat"])
    with pytest.raises(lasercell.InputError, match="instances"):
        lasercell.localize_parts(cloud, [(runner.models[0], 0)])
    with pytest.raises(lasercell.InputError, match="lines of sight"):
        lasercell.localize_parts(cloud, [runner.models[0]], line_of_sight=np.ones((3, 3)))
    with pytest.raises(lasercell.InputError, match="region of interest"):
        lasercell.localize_parts(cloud, [runner.models[0]],
                                 roi=([1e5, 1e5, 1e5], [1e5 + 1, 1e5 + 1, 1e5 + 1]))
    with pytest.raises(lasercell.OptionError, match="bogus"):
        lasercell.localize_parts(cloud, [runner.models[0]], options={"bogus": 1})
