"""openpi protocol: wire compatibility with openpi-client, reconnect, and a dead server failing cleanly."""

import socket
import time

import numpy as np
import pytest

from realm_ms.eval.policies import PolicyInput, make_policy
from realm_ms.eval.policies.openpi_server import OpenPIServer, hold_infer
from realm_ms.eval.policies.openpi_wire import packb, resize_with_pad, unpackb

OBS = {
    "observation/exterior_image_1_left": np.arange(224 * 224 * 3, dtype=np.uint8).reshape(224, 224, 3),
    "observation/joint_position": np.linspace(-1, 1, 7),
    "observation/gripper_position": np.array([0.25]),
    "prompt": "pick up the apple",
    "scalar": np.float32(1.5),
}


def _batch(n=2):
    rng = np.random.default_rng(0)
    state = np.tile(np.array([0.0, -0.6, 0.0, -2.5, 0.0, 1.9, 0.0, 0.0], np.float32), (n, 1))
    return PolicyInput(state=state, instructions=["pick up the apple"] * n,
                       images={c: rng.integers(0, 255, (n, 36, 64, 3), dtype=np.uint8) for c in ("exterior_1", "exterior_2", "wrist")})


def test_wire_roundtrip():
    back = unpackb(packb(OBS))
    assert np.array_equal(back["observation/exterior_image_1_left"], OBS["observation/exterior_image_1_left"])
    assert back["observation/joint_position"].dtype == np.float64 and back["prompt"] == OBS["prompt"]
    assert isinstance(back["scalar"], np.float32) and back["scalar"] == np.float32(1.5)
    with pytest.raises(ValueError):
        packb({"x": np.array([object()])})


def test_wire_and_resize_match_openpi_client():
    msgpack_numpy = pytest.importorskip("openpi_client.msgpack_numpy", reason="openpi-client (installed --no-deps) not present")
    image_tools = pytest.importorskip("openpi_client.image_tools")
    assert packb(OBS) == msgpack_numpy.packb(OBS)  # byte-identical encoding
    theirs = msgpack_numpy.unpackb(packb(OBS))
    assert np.array_equal(theirs["observation/exterior_image_1_left"], OBS["observation/exterior_image_1_left"])
    img = np.random.default_rng(0).integers(0, 255, (2, 180, 320, 3), dtype=np.uint8)
    assert np.array_equal(resize_with_pad(img, 224, 224), image_tools.resize_with_pad(img, 224, 224))


def test_client_against_server_and_openpi_client():
    with OpenPIServer(hold_infer, metadata={"name": "hold"}) as srv:
        pol = make_policy(f"openpi:{srv.address}")
        out = pol.act(_batch(2))
        assert out.errors is None and out.actions.shape == (2, 10, 8)
        assert np.allclose(out.actions[:, :, :7], _batch(2).state[:, None, :7], atol=1e-6)
        assert pol.metadata == {"name": "hold"} and srv.requests == 2
        wcp = pytest.importorskip("openpi_client.websocket_client_policy", reason="openpi-client not present")
        client = wcp.WebsocketClientPolicy(srv.host, srv.port)  # openpi's own client talks to our server
        assert client.get_server_metadata() == {"name": "hold"}
        assert client.infer(pol.request(_batch(1), 0))["actions"].shape == (10, 8)
        pol.close()


def test_groot_format_requests_three_views():
    seen = {}

    def infer(obs):
        seen.update(obs)
        return {"action.joint_position": np.zeros((16, 7)), "action.gripper_position": np.ones((16, 1))}

    with OpenPIServer(infer) as srv:
        pol = make_policy(f"openpi:{srv.address}", openpi_format="groot")
        out = pol.act(_batch(1))
        assert out.actions.shape == (1, 16, 8) and np.all(out.actions[..., 7] == 1)
        assert seen["video.exterior_image_2"].shape == (1, 36, 64, 3) and seen["state.joint_position"].shape == (1, 7)
        assert seen["prompt"] == ["pick up the apple"]
        pol.close()


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_dead_server_fails_rows_and_reconnects_after_restart():
    port = _free_port()
    pol = make_policy(f"openpi:127.0.0.1:{port}", openpi_wait_s=1.0)
    t = time.monotonic()
    out = pol.act(_batch(2))  # nobody listening: each row fails with a clear message, no exception
    assert time.monotonic() - t < 10
    assert out.errors and all("unreachable" in e for e in out.errors)
    with OpenPIServer(hold_infer, port=port):
        assert pol.act(_batch(1)).errors is None  # back up: the next round connects again
    srv = OpenPIServer(hold_infer, port=port).start()
    try:
        assert pol.act(_batch(1)).errors is None  # the old connection died with the old server: reconnected
    finally:
        srv.stop()
    pol.close()


def test_server_error_text_frame_is_reported():
    def boom(obs):
        raise ValueError("bad observation")

    with OpenPIServer(boom) as srv:
        pol = make_policy(f"openpi:{srv.address}", openpi_wait_s=1.0)
        out = pol.act(_batch(1))
        assert out.errors and "ValueError: bad observation" in out.errors[0]
        pol.close()


# ---- concurrent serving, several servers, action spaces --------------------------------------------
class _Probe:
    """Echoes the row's joints (so order is checkable), sleeps, and records the peak concurrency."""

    def __init__(self, sleep=0.05):
        import threading

        self.sleep, self.lock, self.now, self.peak = sleep, threading.Lock(), 0, 0

    def __call__(self, obs):
        with self.lock:
            self.now += 1
            self.peak = max(self.peak, self.now)
        time.sleep(self.sleep)
        with self.lock:
            self.now -= 1
        q = np.asarray(obs["observation/joint_position"], dtype=np.float64).reshape(7)
        return {"actions": np.concatenate([np.tile(q, (4, 1)), np.zeros((4, 1))], axis=1)}


def _distinct_batch(n):
    b = _batch(n)
    b.state[:, 0] = np.arange(n) * 0.1  # each row's joint 0 names its slot
    return b


def test_rows_spread_over_servers_concurrently_and_come_back_in_order():
    probe = _Probe()
    servers = [OpenPIServer(probe).start() for _ in range(3)]
    try:
        pol = make_policy("openpi:" + ",".join(s.address for s in servers))
        out = pol.act(_distinct_batch(9))
        assert out.errors is None and out.actions.shape == (9, 4, 8)
        assert np.allclose(out.actions[:, 0, 0], np.arange(9) * 0.1, atol=1e-6)  # slot order kept
        assert all(s.requests >= 1 for s in servers) and sum(s.requests for s in servers) == 9
        assert probe.peak >= 2  # requests really overlapped
        assert pol.spec() == "openpi:" + ",".join(s.address for s in servers)
        pol.close()
    finally:
        for s in servers:
            s.stop()


def test_in_flight_requests_are_bounded():
    probe = _Probe()
    servers = [OpenPIServer(probe).start() for _ in range(4)]
    try:
        pol = make_policy("openpi:" + ",".join(s.address for s in servers), openpi_max_in_flight=2)
        assert pol.act(_distinct_batch(8)).errors is None
        assert probe.peak <= 2
        seq = make_policy(f"openpi:{servers[0].address}")  # one server, one connection: one at a time
        probe.peak = 0
        assert seq.act(_distinct_batch(4)).errors is None and probe.peak == 1
        pol.close()
        seq.close()
    finally:
        for s in servers:
            s.stop()


def test_a_dead_server_fails_only_its_rows():
    with OpenPIServer(hold_infer) as live:
        dead = f"127.0.0.1:{_free_port()}"
        pol = make_policy(f"openpi:{live.address},{dead}", openpi_wait_s=1.0)
        out = pol.act(_batch(6))
        assert out.errors is not None
        failed = [e for e in out.errors if e]
        assert failed and all(dead in e and "unreachable" in e for e in failed)
        assert len(failed) < 6 and live.requests == 6 - len(failed)
        pol.close()


def test_server_metadata_declares_the_action_space():
    def cartesian(obs):
        return {"actions": np.full((5, 7), 0.5)}

    with OpenPIServer(cartesian, metadata={"action_space": "cartesian_velocity", "gripper_action_space": "position"}) as srv:
        pol = make_policy(f"openpi:{srv.address}")
        assert pol.env_action_space() == {"action_space": "cartesian_velocity", "gripper_action_space": "position"}
        out = pol.act(_batch(2))
        assert out.errors is None and out.actions.shape == (2, 5, 7)
        pol.close()
        joint = make_policy(f"openpi:{srv.address}", action_space="joint_velocity")  # the flag wins; 7-D replies are refused
        out = joint.act(_batch(1))
        assert out.errors and "expected (T, 8)" in out.errors[0]
        joint.close()


def test_velocity_chunks_from_a_server_drive_an_episode_to_success(tmp_path):
    """A stand-in server answers the scripted expert's recorded joint velocities, 8 per request;
    ``realm eval`` in joint_velocity space (declared by the server) replays them to success."""
    from realm_ms.eval import evaluate
    from realm_ms.eval.policies.openpi_server import ReplayInfer, expert_actions
    from realm_ms.eval.protocol import PRESETS
    from realm_ms.eval.records import read_records

    actions = expert_actions("REALM-PickApple-v1", 0, 200, action_space="joint_velocity")
    meta = {"action_space": "joint_velocity", "gripper_action_space": "velocity"}
    with OpenPIServer(ReplayInfer(actions, chunk=8), metadata=meta) as srv:
        proto = PRESETS["realm"].with_overrides(episodes=1, seed=0, max_steps=len(actions) + 8, replan_every=8)
        evaluate(f"openpi:{srv.address}", ["REALM-PickApple-v1"], ["Default"], proto, tmp_path / "run", workers=1,
                 backend="cpu", camera_size=(64, 36), quality=False, progress=False, quiet=True)
    (rec,) = read_records(tmp_path / "run" / "records.jsonl")
    assert rec["status"] == "ok" and rec["success"], rec
    assert rec["action_space"] == "joint_velocity:velocity"
