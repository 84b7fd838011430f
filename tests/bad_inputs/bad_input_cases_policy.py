"""More of the bad-input corpus: policy servers and what they answer. Server addresses (strict,
before any work), ``--policy-latency``, and stand-in openpi / RoboArena servers that answer wrongly
in each way: bad metadata or configs end ``realm eval`` in one line naming the server (exit 2); bad
replies become that episode's error record naming the server and what was wrong (exit 1, the run
goes on); never a traceback, a hang, or actions silently used."""

from __future__ import annotations

import contextlib
import io
import json
import time

import numpy as np

from bad_input_cases import Case, cli

TASK = "REALM-PushSwitch-v1"
RUN = f"--tasks {TASK} --perturbations Default --episodes 1 --max-steps 4 --workers 1 --no-progress --no-quality"


def _ev(policy: str, out: str = "{root}/ev_pol", extra: str = "") -> str:
    return f"eval --policy {policy} {RUN} --out {out} {extra}".strip()


CASES: list[Case] = [
    # ------------------------------------------------------------------------ addresses, parsed before any work
    cli("policy-openpi-ipv6-unbracketed", _ev("openpi:::1:8000"), r"an IPv6 host goes in brackets, e\.g\. \[::1\]:8000"),
    cli("policy-openpi-semicolon", _ev("openpi:127.0.0.1:1;127.0.0.1:2"), r"unexpected character ';' \(separate servers with ','\)"),
    cli("policy-openpi-http-scheme", _ev("openpi:http://127.0.0.1:8000"), r"no scheme \(ws://, http://\) goes in front"),
    cli("policy-openpi-ws-scheme", _ev("openpi:ws://127.0.0.1:8000"), r"no scheme"),
    cli("policy-openpi-trailing-comma", _ev("openpi:127.0.0.1:8000,"), r"an empty entry \(a stray ','\)"),
    cli("policy-openpi-no-port", _ev("openpi:localhost"), r"bad server address 'localhost': no port"),
    cli("policy-openpi-port-text", _ev("openpi:localhost:http"), r"the port 'http' is not a number"),
    cli("policy-openpi-bad-ipv4", _ev("openpi:10.0.0.256:8000"), r"'10\.0\.0\.256' is not an IPv4 address"),
    cli("policy-openpi-bad-ipv6", _ev("openpi:[::g]:8000"), r"'::g' is not an IPv6 address"),
    cli("policy-openpi-user-at-host", _ev("openpi:me@gpu:8000"), r"unexpected character '@'"),
    cli("policy-roboarena-no-address", _ev("roboarena"), r"--policy roboarena needs the server address: roboarena:HOST:PORT"),
    cli("policy-roboarena-port-70000", _ev("roboarena:127.0.0.1:70000"), r"port: must be <= 65535, got 70000"),
    cli("policy-roboarena-ipv6-unbracketed", _ev("roboarena:::1:8000"), r"an IPv6 host goes in brackets"),
    cli("policy-roboarena-bad-action-space", _ev("roboarena:127.0.0.1:1", extra="--action-space warp"),
        r"--action-space: unknown action_space 'warp'"),
    cli("policy-roboarena-unreachable", _ev("roboarena:127.0.0.1:1", extra="--openpi-wait 0.5"),
        r"roboarena server 127\.0\.0\.1:1 unreachable for 0\.5 s"),
    # ------------------------------------------------------------------------ --policy-latency
    cli("policy-latency-negative", _ev("zero", extra="--policy-latency -0.1"), r"argument --policy-latency: must be >= 0"),
    cli("policy-latency-nan", _ev("zero", extra="--policy-latency nan"), r"argument --policy-latency: must be a finite number"),
    cli("policy-latency-inf", _ev("zero", extra="--policy-latency inf"), r"argument --policy-latency: must be a finite number"),
    cli("policy-latency-text", _ev("zero", extra="--policy-latency slow"), r"argument --policy-latency: expected a single number"),
    cli("policy-latency-ms", _ev("zero", extra="--policy-latency 300ms"), r"argument --policy-latency: expected a single number"),
    cli("policy-latency-huge", _ev("zero", extra="--policy-latency 300"), r"argument --policy-latency: 300 s is more than 60 s"),
]


# ---------------------------------------------------------------------------- stand-in servers answering wrongly
def _run_against(server, root, name: str, extra: tuple[str, ...] = ()):
    """``realm eval`` (in-process) against ``server``; (exit code, stderr, records)."""
    from realm_ms.cli import main

    out = root / f"pol_{name}"
    err = io.StringIO()
    with server as srv, contextlib.redirect_stderr(err):
        kind = "roboarena" if type(srv).__name__ == "RoboArenaServer" else "openpi"
        argv = ["eval", "--policy", f"{kind}:{srv.address}", *RUN.split(), "--camera-size", "64x36", "--openpi-wait", "1", "--out", str(out), *extra]
        try:
            code = main(argv)
        except SystemExit as e:
            code = e.code
        address = srv.address
    recs = [json.loads(x) for x in (out / "records.jsonl").read_text().splitlines()] if (out / "records.jsonl").exists() else []
    return code, err.getvalue(), recs, address


def _openpi(reply=None, metadata=None):
    from realm_ms.eval.policies.openpi_server import OpenPIServer

    return OpenPIServer(reply if callable(reply) else (lambda obs: reply), metadata=metadata)


def _roboarena(reply=None, config=None):
    from realm_ms.eval.policies.roboarena_server import RoboArenaServer

    hold = lambda obs: np.concatenate([np.tile(obs["observation/joint_position"], (4, 1)), np.zeros((4, 1))], 1)  # noqa: E731
    return RoboArenaServer(hold if reply is None else (reply if callable(reply) else (lambda obs: reply)), config)


def _reply_case(id: str, make, error: str, extra: tuple[str, ...] = ()) -> Case:
    """A server whose replies are wrong: exit 1, one error record naming the server and ``error``."""

    def call(root):
        return _run_against(make(), root, id, extra)

    def check(result):
        code, err, recs, address = result
        assert "Traceback" not in err, err
        assert code == 1, (code, err[-2000:])
        (rec,) = recs
        assert rec["status"] == "error" and address in rec["error"] and __import__("re").search(error, rec["error"]), rec["error"]

    return Case(f"policy-reply-{id}", call=call, check=check, accepted=f"an error record naming the server: {error}", env=True)


def _refused_case(id: str, make, error: str) -> Case:
    """A server whose metadata / config realm-ms cannot use: exit 2, one line naming the server, no records."""

    def call(root):
        return _run_against(make(), root, id)

    def check(result):
        code, err, recs, address = result
        assert "Traceback" not in err, err
        last = [x for x in err.splitlines() if x.strip()][-1]
        assert code == 2 and address in last and __import__("re").search(error, last), (code, last)
        assert last.startswith("realm") and "--action-space" not in last and not recs

    return Case(f"policy-refused-{id}", call=call, check=check, accepted=f"refused in one line naming the server: {error}", env=True)


def _slow(obs):
    time.sleep(3)
    return {"actions": np.zeros((1, 8))}


CASES += [
    _reply_case("openpi-nan", lambda: _openpi({"actions": np.full((4, 8), np.nan)}), r"actions contain NaN or Inf"),
    _reply_case("openpi-empty-chunk", lambda: _openpi({"actions": np.zeros((0, 8))}), r"an empty action chunk"),
    _reply_case("openpi-1xTx8", lambda: _openpi({"actions": np.zeros((1, 4, 8))}), r"shape \(1, 4, 8\); expected \(T, 8\)"),
    _reply_case("openpi-scalar", lambda: _openpi({"actions": np.float32(1.0)}), r"shape \(\)"),
    _reply_case("openpi-strings", lambda: _openpi({"actions": ["open", "close"]}), r"dtype <U5; expected numbers"),
    _reply_case("openpi-1e39", lambda: _openpi({"actions": np.full((4, 8), 1e39)}), r"1e\+39 is far outside the joint_position"),
    _reply_case("openpi-7-wide", lambda: _openpi({"actions": np.zeros((4, 7))}), r"shape \(4, 7\); expected \(T, 8\)"),
    _reply_case("openpi-no-actions", lambda: _openpi({"action": np.zeros((4, 8))}), r"has no 'actions'"),
    _reply_case("openpi-list-reply", lambda: _openpi([1, 2, 3]), r"its reply is a list, not a map"),
    _reply_case("openpi-not-msgpack", lambda: _openpi(b"\xc1\xc1 not msgpack"), r"its reply is not msgpack-numpy"),
    _reply_case("openpi-text-frame", lambda: _openpi("Traceback (most recent call last):\n  ...\nKeyError: 'observation/image'"),
                r"error: KeyError: 'observation/image'"),
    _reply_case("openpi-raises", lambda: _openpi(lambda obs: 1 / 0), r"error: ZeroDivisionError: division by zero"),
    _reply_case("roboarena-nan", lambda: _roboarena(np.full((2, 8), np.inf)), r"actions contain NaN or Inf"),
    _reply_case("roboarena-empty", lambda: _roboarena(np.zeros((0, 8))), r"an empty action chunk"),
    _reply_case("roboarena-object", lambda: _roboarena({"actions": {"q": 1}}), r"actions are a dict"),
    _reply_case("roboarena-velocity-far", lambda: _roboarena(np.full((2, 8), 50.0), dict(action_space="joint_velocity")),
                r"far outside the joint_velocity:position bounds"),
    _reply_case("roboarena-traceback", lambda: _roboarena(lambda obs: obs["observation/stereo"]), r"error: KeyError: 'observation/stereo'"),
    _refused_case("openpi-metadata-list", lambda: _openpi({"actions": np.zeros((1, 8))}, metadata=[1, 2]), r"its metadata is a list, not a map"),
    _refused_case("openpi-metadata-bogus-space", lambda: _openpi({"actions": np.zeros((1, 8))}, metadata={"action_space": "teleport"}),
                  r"its metadata declares action_space 'teleport'; known: joint_position"),
    _refused_case("openpi-metadata-bogus-gripper", lambda: _openpi({"actions": np.zeros((1, 8))},
                                                                   metadata={"action_space": "joint_velocity", "gripper_action_space": "magnet"}),
                  r"declares gripper_action_space 'magnet'"),
    _refused_case("openpi-metadata-not-msgpack", lambda: _openpi({"actions": np.zeros((1, 8))}, metadata=b"\xc1"),
                  r"its metadata is not msgpack-numpy"),
    _refused_case("roboarena-stereo", lambda: _roboarena(config=dict(needs_stereo_camera=True)), r"realm-ms has no stereo cameras"),
    _refused_case("roboarena-cartesian", lambda: _roboarena(config=dict(action_space="cartesian_velocity")),
                  r"declares action_space 'cartesian_velocity'; RoboArena servers use joint_position or joint_velocity"),
    _refused_case("roboarena-three-cameras", lambda: _roboarena(config=dict(n_external_cameras=3)), r"n_external_cameras is 3"),
    _refused_case("roboarena-resolution-text", lambda: _roboarena(config=dict(image_resolution="224x224")), r"image_resolution is '224x224'"),
    _refused_case("roboarena-config-list", lambda: _roboarena(config=[224, 224]), r"its metadata is a list, not a map"),
    _refused_case("roboarena-config-text-frame", lambda: _roboarena(config="hello"), r"error: hello"),
]


def _silent_call(root):
    """A server that never answers: the request times out as 'no reply', not 'unreachable', and no hang."""
    from realm_ms.eval.policies import PolicyInput
    from realm_ms.eval.policies.openpi import OpenPIPolicy

    with _openpi(_slow) as srv:
        pol = OpenPIPolicy(srv.address, max_wait_s=1.0, reply_timeout_s=0.5)
        b = PolicyInput(state=np.zeros((1, 8), np.float32), instructions=["x"], slots=[0],
                        images={c: np.zeros((1, 36, 64, 3), np.uint8) for c in ("exterior_1", "wrist")})
        t = time.monotonic()
        out = pol.act(b)
        pol.close()
        return out.errors, time.monotonic() - t, srv.address


def _silent_check(result):
    errors, wall, address = result
    assert errors == [f"openpi server {address}: no reply within 0.5 s"] and wall < 5, (errors, wall)


CASES += [Case("policy-reply-openpi-silent", call=_silent_call, check=_silent_check, accepted="'no reply within 0.5 s', not 'unreachable'")]
