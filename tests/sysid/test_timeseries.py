"""Data validation, seeded split, npz and LeRobot v3.0 reading."""

import numpy as np
import pytest

from realm_ms.sysid.data_io import joint_limits, load_dir, load_split, read_lerobot, write_npz
from realm_ms.sysid.timeseries import DataError, Trajectory, split, validate

LIMITS = joint_limits()
HOME = np.array([0.0, -0.63, 0.0, -2.5, 0.0, 1.9, 0.0])


def traj(n=60, name="a", **kw):
    t = np.arange(n) / 15.0
    q = HOME + 0.01 * np.sin(t)[:, None]
    d = dict(t=t, q=q, q_cmd=q.copy())
    d.update(kw)
    return Trajectory(name, d["t"], d["q"], d["q_cmd"])


def test_valid_trajectory_passes():
    out = validate(traj(), LIMITS)
    assert out.q.shape == (60, 7) and out.t[0] == 0


@pytest.mark.parametrize("kw, msg", [
    (dict(q=np.full((60, 7), np.nan)), "NaN/inf"),
    (dict(q=np.zeros((60, 6))), r"shape \(60, 6\)"),
    (dict(q=np.zeros((59, 7))), "59 samples"),
    (dict(t=np.r_[np.arange(30), np.arange(30)] / 15.0), "not strictly increasing"),
    (dict(q_cmd=np.rad2deg(np.repeat(HOME[None], 60, 0))), "degrees"),
    (dict(q_cmd=np.repeat((HOME + [0, 0, 0, 3.0, 0, 0, 0])[None], 60, 0)), "outside the joint limits"),
])
def test_bad_data_is_refused_with_a_clear_message(kw, msg):
    with pytest.raises(DataError, match=msg):
        validate(traj(**kw), LIMITS)


def test_measured_joints_a_little_past_the_limits_warn_far_past_are_refused():
    """A real arm reads a little past the URDF's limits (DROID: joint 6 at 3.82 against 3.7525): a
    warning naming the joint; far past them (wrong joint order) an error."""
    from realm_ms.sysid.timeseries import DataWarning

    hi6 = LIMITS[5, 1]
    q = np.repeat(HOME[None], 60, 0)
    q[10:20, 5] = hi6 + 0.07
    with pytest.warns(DataWarning, match=r"joint 6 = .* past the model's joint limits .*17%"):
        out = validate(traj(q=q, q_cmd=np.repeat(HOME[None], 60, 0)), LIMITS)
    assert np.array_equal(out.q, q)
    q[10:20, 5] = hi6 + 0.3
    with pytest.raises(DataError, match="measured joint 6 .* by more than 0.25 rad"):
        validate(traj(q=q, q_cmd=np.repeat(HOME[None], 60, 0)), LIMITS)


def test_too_few_samples():
    with pytest.raises(DataError, match="only 10 samples"):
        validate(traj(n=10), LIMITS)


def test_split_is_seeded_by_trajectory():
    trajs = [traj(name=f"t{i}") for i in range(10)]
    a = split(trajs, 0.3, seed=3)
    b = split(list(reversed(trajs)), 0.3, seed=3)
    assert [t.name for t in a[1]] == [t.name for t in b[1]] and len(a[1]) == 3
    assert {t.name for t in a[0]} | {t.name for t in a[1]} == {f"t{i}" for i in range(10)}
    assert [t.name for t in split(trajs, 0.3, seed=4)[1]] != [t.name for t in a[1]]
    with pytest.raises(DataError, match="needs >= 20 s"):
        split(trajs[:1])  # 4 s


def test_a_single_long_log_is_split_into_time_blocks():
    """One 65 s recording: 6 contiguous blocks of ~10.8 s, 2 held out (seeded); together they are the
    log, sample for sample, and every array is cut at the same rows."""
    long = traj(n=65 * 15, name="franka", tau=None)
    long.tau = np.random.default_rng(0).normal(size=(len(long.t), 7))
    train, held = split([long], 0.3, seed=0)
    assert len(train) == 4 and len(held) == 2
    parts = sorted(train + held, key=lambda b: b.meta["block_start_s"])
    assert all(b.meta["block_of"] == "franka" and b.name.startswith("franka[") for b in parts)
    np.testing.assert_array_equal(np.concatenate([b.q for b in parts]), long.q)
    np.testing.assert_array_equal(np.concatenate([b.tau for b in parts]), long.tau)
    np.testing.assert_allclose(np.concatenate([b.t + b.meta["block_start_s"] for b in parts]), long.t)
    assert all(b.t[0] == 0 and b.duration >= 10 for b in parts)
    assert [b.name for b in split([long], 0.3, seed=0)[1]] == [b.name for b in held]


def test_npz_round_trip_and_directory_layouts(tmp_path):
    for i in range(3):
        write_npz(tmp_path / "all" / f"x{i}.npz", traj(name=f"x{i}"))
    loaded = load_dir(tmp_path / "all")
    assert [t.name for t in loaded] == ["x0", "x1", "x2"]
    tr, he = load_split(tmp_path / "all", seed=0)
    assert len(tr) == 2 and len(he) == 1
    write_npz(tmp_path / "s" / "train" / "a.npz", traj(name="a"))
    write_npz(tmp_path / "s" / "heldout" / "b.npz", traj(name="b"))
    tr, he = load_split(tmp_path / "s")
    assert [t.name for t in tr] == ["a"] and [t.name for t in he] == ["b"]
    # synth's layout read whole (what `compare` does): train then held-out
    assert [t.name for t in load_dir(tmp_path / "s")] == ["a", "b"]
    (tmp_path / "empty").mkdir()
    with pytest.raises(DataError, match="no .npz"):
        load_dir(tmp_path / "empty")
    np.savez(tmp_path / "bad.npz", t=np.arange(30) / 15.0, q=np.zeros((30, 7)))
    with pytest.raises(DataError, match="missing key"):
        load_dir(tmp_path / "bad.npz")


def test_lerobot_v3_dataset(tmp_path):
    """A dataset written by lerobot's own writer (DROID convention) reads as trajectories."""
    pytest.importorskip("lerobot")
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    feats = {"observation.state": {"dtype": "float32", "shape": (8,), "names": None},
             "action": {"dtype": "float32", "shape": (8,), "names": None}}
    ds = LeRobotDataset.create(repo_id="local/droid_sysid_test", fps=15, features=feats, root=tmp_path / "ds", use_videos=False)
    for ep in range(2):
        for i in range(30):
            q = np.r_[HOME + 0.001 * i, 0.5].astype(np.float32)
            ds.add_frame({"observation.state": q, "action": q + np.float32(0.01), "task": "sysid"})
        ds.save_episode()
    ds.finalize()
    trajs = read_lerobot(tmp_path / "ds")
    assert len(trajs) == 2 and trajs[0].q.shape == (30, 7) and trajs[0].gripper is not None
    np.testing.assert_allclose(trajs[1].q_cmd - trajs[1].q, 0.01, atol=1e-6)
    assert trajs[0].t[1] == pytest.approx(1 / 15)
    assert len(load_dir(tmp_path / "ds")) == 2
