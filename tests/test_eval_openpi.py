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
