"""Policy replies and server metadata checked where they arrive, addresses parsed strictly: a bad
reply is one episode's error record naming its source, never the end of the run."""

import socket

import numpy as np
import pytest

from realm_ms.agents.droid_action_spaces import make_action_space
from realm_ms.eval.policies import Policy, PolicyInput, PolicyOutput, make_policy
from realm_ms.eval.policies.openpi_server import OpenPIServer, hold_infer
from realm_ms.eval.policies.replies import ReplyError, check_chunk, check_output
from realm_ms.eval.policies.websocket_client import parse_addresses

JP = make_action_space("joint_position")
JV = make_action_space("joint_velocity", "position")
Q = np.array([0.0, -0.6, 0.0, -2.5, 0.0, 1.9, 0.0, 0.0])


@pytest.mark.parametrize("actions, match", [
    (np.full((3, 8), np.nan), "NaN or Inf"),
    (np.zeros((0, 8)), "empty action chunk"),
    (np.zeros((1, 3, 8)), r"shape \(1, 3, 8\)"),
    (np.float64(1.0), r"shape \(\)"),
    ("abc", "a str, not an array"),
    (np.array([["a"] * 8]), "dtype <U1"),
    (np.ones((2, 8), bool), "dtype bool"),
    ([[1, 2], [3]], "not an array of numbers"),
    (np.zeros((2, 7)), r"expected \(T, 8\) for the joint_position"),
    (np.full((1, 8), 1e39), r"far outside"),
    (np.tile(Q, (2, 1)) + [6, 0, 0, 0, 0, 0, 0, 0], r"action 0, dim 0 = 6 is far outside"),
])
def test_bad_chunks_say_what_is_wrong(actions, match):
    with pytest.raises(ReplyError, match=match):
        check_chunk(actions, JP, "the server")


def test_good_chunks_pass():
    assert check_chunk(Q, JP, "s").shape == (1, 8)  # one action
    assert check_chunk(np.tile(Q, (4, 1)) + 0.3, JP, "s").dtype == np.float32  # a small overshoot is the env's to clip
    assert check_chunk(np.full((2, 8), 1.2), JV, "s").shape == (2, 8)
    with pytest.raises(ReplyError, match="far outside the joint_velocity:position bounds"):
        check_chunk(np.full((2, 8), 2.0), JV, "s")


def test_check_output_fails_rows_not_the_batch():
    a = np.tile(Q, (3, 2, 1)).astype(np.float32)
    a[1, 0, 3] = np.nan
    _, errors = check_output(PolicyOutput(a), 3, {}, "lerobot:x")
    assert errors[0] is None and errors[2] is None and "lerobot:x: actions contain NaN" in errors[1]
    _, errors = check_output(PolicyOutput(np.zeros((3, 8))), 3, {}, "p")  # not (B, T, 8): every row
    assert all("expected (3, T, 8)" in e for e in errors)
    _, errors = check_output(PolicyOutput("nope"), 2, {}, "p")
    assert len(errors) == 2 and all(errors)


@pytest.mark.parametrize("text, match", [
    ("::1:8000", r"an IPv6 host goes in brackets"),
    ("h:1;h:2", r"unexpected character ';' \(separate servers with ','\)"),
    ("http://h:1", r"no scheme"),
    ("ws://h:1", r"no scheme"),
    ("h:1,,h:2", r"an empty entry"),
    ("h:1,", r"an empty entry"),
    ("h", r"no port"),
    (":8000", r"no host"),
    ("h:port", r"the port 'port' is not a number"),
    ("h:+80", r"unexpected character '\+'"),
    ("h:80x", r"the port '80x' is not a number"),
    ("h:99999", r"port: must be <= 65535"),
    ("h:0", r"port: must be >= 1"),
    ("[::1", r"an IPv6 host is \[ADDRESS\]:PORT"),
    ("[zz::1]:80", r"'zz::1' is not an IPv6 address"),
    ("300.1.1.1:80", r"'300.1.1.1' is not an IPv4 address"),
    ("-bad-:80", r"'-bad-' is not a host name"),
    ("h h:80", r"unexpected character ' '"),
    ("", r"needs a server address"),
])
def test_addresses_are_parsed_strictly(text, match):
    with pytest.raises(ValueError, match=match):
        parse_addresses(text, "openpi")


def test_good_addresses():
    got = parse_addresses("localhost:8000, 10.0.0.2:1,[::1]:9000,gpu-3.lab.example.org:65535,policy_server:80", "openpi")
    assert [str(a) for a in got] == ["localhost:8000", "10.0.0.2:1", "[::1]:9000", "gpu-3.lab.example.org:65535", "policy_server:80"]
    assert got[2].uri == "ws://[::1]:9000"


def test_an_ipv6_server_is_reachable_in_brackets():
    if not socket.has_ipv6:
        pytest.skip("no IPv6 on this machine")
    try:
        srv = OpenPIServer(hold_infer, host="::1").start()
    except OSError:
        pytest.skip("cannot bind ::1")
    try:
        pol = make_policy(f"openpi:[::1]:{srv.port}")
        assert pol.act(_batch(1)).errors is None
        pol.close()
    finally:
        srv.stop()


def _batch(n=1):
    return PolicyInput(state=np.tile(Q.astype(np.float32), (n, 1)), instructions=["x"] * n,
                       images={c: np.zeros((n, 36, 64, 3), np.uint8) for c in ("exterior_1", "exterior_2", "wrist")}, slots=list(range(n)))


@pytest.mark.parametrize("metadata, match", [
    ([1, 2], r"openpi server 127\.0\.0\.1:\d+: its metadata is a list, not a map"),
    ({"action_space": "warp_drive"}, r"openpi server 127\.0\.0\.1:\d+: its metadata declares action_space 'warp_drive'"),
    ({"action_space": "joint_velocity", "gripper_action_space": 3}, r"declares gripper_action_space 3"),
    (b"\xc1", r"its metadata is not msgpack-numpy"),
])
def test_bad_metadata_names_the_server_not_a_flag(metadata, match):
    from realm_ms.errors import UserError
    from realm_ms.eval.policies import policy_action_space

    with OpenPIServer(hold_infer, metadata=metadata) as srv:
        pol = make_policy(f"openpi:{srv.address}", openpi_wait_s=1.0)
        with pytest.raises(UserError, match=match) as e:
            policy_action_space(pol)
        assert "--action-space" not in str(e.value)
        out = pol.act(_batch(1))  # at run time: the row's error
        assert out.errors and srv.address in out.errors[0]
        pol.close()


@pytest.mark.parametrize("reply, match", [
    ({"actions": np.full((4, 8), np.nan)}, "NaN or Inf"),
    ({"actions": np.zeros((0, 8))}, "empty action chunk"),
    ({"actions": np.zeros((1, 4, 8))}, "shape (1, 4, 8)"),
    ({"actions": np.float64(2.0)}, "shape ()"),
    ({"actions": "left"}, "a str, not an array"),
    ({"actions": np.full((2, 8), 1e39)}, "far outside"),
    ({"action": np.zeros((2, 8))}, "has no 'actions'"),
    (np.zeros((2, 8)), "its reply is a ndarray, not a map"),
    (b"\x92\x01\x02", "its reply is a list, not a map"),
    (b"\xc1garbage", "not msgpack-numpy"),
])
def test_bad_openpi_replies_name_the_server(reply, match):
    with OpenPIServer(lambda obs: reply) as srv:
        pol = make_policy(f"openpi:{srv.address}", openpi_wait_s=1.0)
        out = pol.act(_batch(2))
        assert out.errors and all(e and f"openpi server {srv.address}" in e and match in e for e in out.errors), out.errors
        assert "unreachable" not in out.errors[0]
        pol.close()


def test_a_server_that_closes_before_its_metadata():
    import threading

    from websockets.sync.server import serve

    server = serve(lambda ws: ws.close(), "127.0.0.1", 0)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        port = server.socket.getsockname()[1]
        pol = make_policy(f"openpi:127.0.0.1:{port}", openpi_wait_s=1.0)
        out = pol.act(_batch(1))
        assert out.errors and out.errors[0].startswith(f"openpi server 127.0.0.1:{port}: closed the connection before sending its metadata")
        pol.close()
        with pytest.raises(ValueError, match="closed the connection before sending its metadata"):
            make_policy(f"roboarena:127.0.0.1:{port}", openpi_wait_s=1.0)
    finally:
        server.shutdown()


def test_a_silent_server_is_not_unreachable():
    import time

    with OpenPIServer(lambda obs: time.sleep(3) or {"actions": np.zeros((1, 8))}) as srv:
        from realm_ms.eval.policies.openpi import OpenPIPolicy

        pol = OpenPIPolicy(srv.address, max_wait_s=1.0, reply_timeout_s=0.5)
        out = pol.act(_batch(1))
        assert out.errors == [f"openpi server {srv.address}: no reply within 0.5 s"]
        pol.close()


class _NaNOnce(Policy):
    """Holds still; its second answer for the first episode is NaN."""

    name = "nan-once"

    def __init__(self):
        self.calls = 0

    def act(self, batch):
        self.calls += 1
        a = np.repeat(batch.state[:, None, :], 4, axis=1)
        if self.calls == 2:
            a[:, 1, 2] = np.nan
        return PolicyOutput(a)


class _Raises(Policy):
    name = "raises"

    def act(self, batch):
        raise RuntimeError("the checkpoint's head has 7 outputs")


@pytest.mark.parametrize("policy, want", [(_NaNOnce(), "nan-once: actions contain NaN or Inf (action 1, dim 2: nan)"),
                                          (_Raises(), "raises: RuntimeError: the checkpoint's head has 7 outputs")])
def test_an_in_process_policys_bad_output_is_an_error_record_and_the_run_goes_on(policy, want):
    from realm_ms.eval.protocol import EpisodeKey
    from realm_ms.eval.runner import RunConfig, run_plan
    from realm_ms.eval.backends.inline import InlineBackend

    cfg = RunConfig(policy=policy.name, max_steps=8, replan_every=4, quality=False)
    be = InlineBackend(cfg, 1)
    recs = []
    try:
        keys = [EpisodeKey("REALM-PickApple-v1", "Default", s) for s in (0, 1)]
        run_plan(keys, policy, be, recs.append, progress_bar=False, replan_every=4)
    finally:
        be.close()
    assert recs[0]["status"] == "error" and recs[0]["error"] == want
    if isinstance(policy, _NaNOnce):
        assert recs[1]["status"] == "ok" and recs[1]["steps"] == 8


def test_export_refuses_a_velocity_server(tmp_path, capsys):
    """A server declaring joint_velocity under `realm export`: one line naming it, exit 2, nothing written."""
    from realm_ms.cli import main

    with OpenPIServer(hold_infer, metadata={"action_space": "joint_velocity"}) as srv:
        code = main(["export", "--policy", f"openpi:{srv.address}", "--tasks", "REALM-PickApple-v1", "--episodes", "1",
                     "--out", str(tmp_path / "ds"), "--width", "64", "--height", "48", "--max-steps", "4"])
        assert srv.requests == 0
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert code == 2 and "acts in joint_velocity:velocity (its server declares it)" in err, err


class _NotAnOutput(Policy):
    name = "bare-array"

    def act(self, batch):
        return np.repeat(batch.state[:, None, :], 2, axis=1)  # an ndarray, not a PolicyOutput


def test_a_policy_returning_a_bare_array_fails_its_episodes_not_the_run():
    from realm_ms.eval.protocol import EpisodeKey
    from realm_ms.eval.runner import RunConfig, run_plan
    from realm_ms.eval.backends.inline import InlineBackend

    be = InlineBackend(RunConfig(policy="bare-array", max_steps=4, replan_every=2, quality=False), 1)
    recs = []
    try:
        run_plan([EpisodeKey("REALM-PickApple-v1", "Default", 0)], _NotAnOutput(), be, recs.append, progress_bar=False, replan_every=2)
    finally:
        be.close()
    assert recs[0]["status"] == "error" and recs[0]["error"] == "bare-array: returned a ndarray, not a PolicyOutput with actions (1, T, 8)", recs[0]
