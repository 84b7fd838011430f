"""RoboArena protocol: the config decides what is sent, resets and sessions per episode, replies
checked, errors named, the expert's chunks replayed to success in both action spaces."""

import socket

import numpy as np
import pytest

from realm_ms.eval.policies import PolicyInput, make_policy
from realm_ms.eval.policies.openpi_wire import resize_with_pad
from realm_ms.eval.policies.openpi_server import ReplayInfer
from realm_ms.eval.policies.roboarena_server import RoboArenaServer

STATE = np.array([0.0, -0.6, 0.0, -2.5, 0.0, 1.9, 0.0, 0.0], np.float32)
ALWAYS = {"observation/joint_position", "observation/cartesian_position", "observation/gripper_position", "prompt"}


def _batch(n=2, slots=None):
    rng = np.random.default_rng(0)
    return PolicyInput(state=np.tile(STATE, (n, 1)), instructions=["pick up the apple"] * n,
                       images={c: rng.integers(0, 255, (n, 36, 64, 3), dtype=np.uint8) for c in ("exterior_1", "exterior_2", "wrist")},
                       slots=list(slots if slots is not None else range(n)))


def _hold(obs):
    q = np.asarray(obs["observation/joint_position"], np.float64)
    return np.concatenate([np.tile(q, (4, 1)), np.ones((4, 1)) * 0.7], axis=1)


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("config, keys", [
    ({}, ALWAYS | {"observation/wrist_image_left", "observation/exterior_image_1_left"}),
    (dict(image_resolution=None, needs_wrist_camera=False, n_external_cameras=2, needs_session_id=True),
     ALWAYS | {"observation/exterior_image_1_left", "observation/exterior_image_2_left", "session_id"}),
    (dict(needs_wrist_camera=False, n_external_cameras=0), ALWAYS),
])
def test_the_config_decides_what_is_sent(config, keys):
    with RoboArenaServer(_hold, config) as srv:
        pol = make_policy(f"roboarena:{srv.address}")
        pol.reset([0, 1])
        b = _batch(2)
        out = pol.act(b)
        assert out.errors is None and out.actions.shape == (2, 4, 8)
        assert np.allclose(out.actions[..., 7], 0.7)  # the gripper position as answered
        assert [set(o) for o in srv.seen] == [keys, keys]  # nothing else (the endpoint is taken off by the server)
        o = srv.seen[0]
        res = config.get("image_resolution", (224, 224))
        for k in keys - ALWAYS - {"session_id"}:
            want = b.images["wrist" if "wrist" in k else "exterior_" + k.split("_")[2]][0]
            assert np.array_equal(o[k], want if res is None else resize_with_pad(want, *res))
        from realm_ms.agents.droid_action_spaces import DroidIK

        assert np.allclose(o["observation/cartesian_position"], DroidIK().pose(STATE[None, :7].astype(np.float64))[0])
        assert o["observation/joint_position"].shape == (7,) and o["observation/gripper_position"].shape == (1,)
        assert o["prompt"] == "pick up the apple"
        # a reset per starting slot, each with its own session id, which its requests then carry
        assert len(srv.resets) == 2 and srv.resets[0]["session_id"] != srv.resets[1]["session_id"]
        if "session_id" in keys:
            assert [x["session_id"] for x in srv.seen] == [r["session_id"] for r in srv.resets]
        cams = pol.obs_request().cameras
        assert set(cams) == {"wrist" if "wrist" in k else "exterior_" + k.split("_")[2] for k in keys - ALWAYS - {"session_id"}}
        pol.reset([1])  # a new episode in slot 1: a new session
        assert len(srv.resets) == 3 and srv.resets[2]["session_id"] not in (srv.resets[0]["session_id"], srv.resets[1]["session_id"])
        pol.close()


def test_action_space_comes_from_the_config():
    with RoboArenaServer(_hold, dict(action_space="joint_velocity")) as srv:
        pol = make_policy(f"roboarena:{srv.address}")
        assert pol.env_action_space() == {"action_space": "joint_velocity", "gripper_action_space": "position"}
        with pytest.raises(ValueError, match="declares action_space joint_velocity"):
            make_policy(f"roboarena:{srv.address}", action_space="joint_position:velocity")
        pol.close()


@pytest.mark.parametrize("config, match", [
    (dict(needs_stereo_camera=True), r"asks for stereo images .* realm-ms has no stereo cameras"),
    (dict(action_space="cartesian_velocity"), r"declares action_space 'cartesian_velocity'"),
    (dict(n_external_cameras=3), r"n_external_cameras is 3; expected 0, 1 or 2"),
    (dict(image_resolution=[224]), r"image_resolution is \[224\]"),
    (dict(needs_wrist_camera="yes"), r"needs_wrist_camera is 'yes'; expected true or false"),
    ([1, 2], r"its metadata is a list, not a map"),
])
def test_configs_realm_ms_cannot_serve_are_refused_naming_the_server(config, match):
    with RoboArenaServer(_hold, config) as srv:
        with pytest.raises(ValueError, match=match) as e:
            make_policy(f"roboarena:{srv.address}", openpi_wait_s=1.0)
        assert f"roboarena server {srv.address}" in str(e.value)


def test_a_traceback_and_close_becomes_the_rows_error():
    def boom(obs):
        raise ValueError("the model ran out of memory")

    with RoboArenaServer(boom) as srv:
        pol = make_policy(f"roboarena:{srv.address}", openpi_wait_s=1.0)
        pol.reset([0])
        out = pol.act(_batch(1))
        assert out.errors == [f"roboarena server {srv.address} error: ValueError: the model ran out of memory"]
        srv.infer = _hold  # the server's next connection works again: the client reconnects
        assert pol.act(_batch(1)).errors is None
        pol.close()


@pytest.mark.parametrize("reply, match", [
    (np.full((4, 8), np.nan), "NaN or Inf"),
    (np.zeros((0, 8)), "empty action chunk"),
    (np.zeros((1, 4, 8)), r"shape \(1, 4, 8\)"),
    (np.float64(3.0), r"shape \(\)"),
    (np.array(["a", "b"]), "dtype <U1"),
    (np.full((2, 8), 1e39), "far outside"),
    ({"action": np.zeros((2, 8))}, "without 'actions'"),
    (b"\xc1\xc1", "not msgpack-numpy"),
])
def test_bad_replies_fail_the_row_naming_the_server(reply, match):
    with RoboArenaServer(lambda obs: reply) as srv:
        pol = make_policy(f"roboarena:{srv.address}", openpi_wait_s=1.0)
        out = pol.act(_batch(2))
        assert out.errors and all(e and srv.address in e and __import__("re").search(match, e) for e in out.errors), out.errors
        pol.close()


def test_rows_keep_to_their_connection_over_several_servers():
    servers = [RoboArenaServer(_hold, dict(needs_session_id=True)).start() for _ in range(2)]
    try:
        pol = make_policy("roboarena:" + ",".join(s.address for s in servers))
        pol.reset([0, 1, 2, 3])
        assert pol.act(_batch(4)).errors is None and pol.act(_batch(4)).errors is None
        for s in servers:  # each server sees the sessions it was reset with, and only those
            assert {x["session_id"] for x in s.seen} == {r["session_id"] for r in s.resets} and len(s.resets) == 2
        pol.close()
    finally:
        for s in servers:
            s.stop()


def test_an_unreachable_server_fails_before_any_work():
    with pytest.raises(ConnectionError, match=r"roboarena server 127\.0\.0\.1:\d+ unreachable for 0\.5 s"):
        make_policy(f"roboarena:127.0.0.1:{_free_port()}", openpi_wait_s=0.5)


def _expert_actions(space: str) -> np.ndarray:
    from realm_ms.eval.policies.openpi_server import expert_actions

    kw = {} if space == "joint_position" else dict(action_space="joint_velocity", gripper_action_space="position")
    return expert_actions("REALM-PickApple-v1", 0, 300, **kw)


@pytest.mark.parametrize("space", ["joint_position", "joint_velocity"])
def test_the_experts_chunks_drive_an_episode_to_success(space, tmp_path):
    """A stand-in RoboArena server answers the scripted expert's recorded actions, 8 per request, in
    the action space its config declares; ``realm eval`` replays them to success."""
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS
    from realm_ms.eval.records import read_records

    actions = _expert_actions(space)
    with RoboArenaServer(ReplayInfer(actions, chunk=8), dict(action_space=space)) as srv:
        proto = PRESETS["realm"].with_overrides(episodes=1, seed=0, max_steps=len(actions) + 8, replan_every=8)
        code = evaluate(f"roboarena:{srv.address}", ["REALM-PickApple-v1"], ["Default"], proto, tmp_path / "run", workers=1,
                        backend="cpu", camera_size=(64, 36), quality=False, progress=False, quiet=True)
        assert len(srv.resets) == 1
    (rec,) = read_records(tmp_path / "run" / "records.jsonl")
    assert code == 0 and rec["status"] == "ok" and rec["success"], rec
    assert rec["action_space"] == f"{space}:position" and rec["policy"] == f"roboarena:{srv.address}"
    assert rec["policy_latency"] == "0" and list(rec["latency_s"]) == [srv.address]


def test_a_failing_server_becomes_an_error_record_and_the_run_goes_on(tmp_path):
    from realm_ms.eval import evaluate
    from realm_ms.eval.protocol import PRESETS
    from realm_ms.eval.records import read_records

    calls = {"n": 0}

    def sometimes(obs):
        calls["n"] += 1
        if calls["n"] == 2:
            raise RuntimeError("CUDA error: an illegal memory access")
        return _hold(obs)

    with RoboArenaServer(sometimes) as srv:
        proto = PRESETS["realm"].with_overrides(episodes=2, seed=0, max_steps=12, replan_every=4)
        code = evaluate(f"roboarena:{srv.address}", ["REALM-PickApple-v1"], ["Default"], proto, tmp_path / "run", workers=1,
                        backend="cpu", camera_size=(64, 36), quality=False, progress=False, quiet=True, policy_options={"openpi_wait_s": 2.0})
    recs = sorted(read_records(tmp_path / "run" / "records.jsonl"), key=lambda r: r["seed"])
    assert code == 1 and [r["status"] for r in recs] == ["error", "ok"]
    assert recs[0]["error"] == f"roboarena server {srv.address} error: RuntimeError: CUDA error: an illegal memory access"
    assert recs[1]["steps"] == 12
