"""openpi websocket policy servers (pi0, pi0-FAST, pi0.5, GR00T-style DROID servers) as a policy.

Protocol (openpi ``WebsocketClientPolicy``): connect to ``ws://HOST:PORT``; the server first sends
its metadata; then each request is one binary msgpack-numpy message (the observation dict) answered
by one binary message (``{"actions": (T, 8)}``); a text frame is a server-side error.

Request formats (``fmt``):
- ``pi0`` (default): ``observation/exterior_image_1_left`` and ``observation/wrist_image_left``
  (224x224 ``resize_with_pad``), ``observation/joint_position`` (7), ``observation/gripper_position``
  (1), ``prompt``;
- ``groot``: ``video.exterior_image_1``, ``video.exterior_image_2``, ``video.wrist_image`` (320x180,
  batch of 1 frame), ``state.joint_position`` (1x7), ``state.gripper_position`` (1x1), ``prompt``;
  answers ``action.joint_position`` / ``action.gripper_position`` (or ``actions``).

A lost connection is retried with exponential back-off for up to ``max_wait_s``; a server that stays
down fails the episodes of that round (``PolicyOutput.errors``), never the run, and the next round
tries again.
"""

from __future__ import annotations

import time

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import ObsRequest, Policy, PolicyInput, PolicyOutput
from realm_ms.eval.policies.openpi_wire import packb, resize_with_pad, unpackb

FORMATS = ("pi0", "groot")


class OpenPIPolicy(Policy):
    name = "openpi"

    def __init__(self, address: str, fmt: str = "pi0", max_wait_s: float = 30.0, api_key: str | None = None, image_size: int = 224):
        if fmt not in FORMATS:
            raise ValueError(f"unknown openpi request format {fmt!r}; known: {', '.join(FORMATS)}")
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise ValueError(f"openpi policy needs HOST:PORT, got {address!r}")
        self.uri = address if address.startswith("ws") else f"ws://{host}:{port}"
        self.address, self.fmt, self.max_wait_s, self.api_key, self.image_size = address, fmt, max_wait_s, api_key, image_size
        self.ws = None
        self.metadata: dict = {}

    def obs_request(self) -> ObsRequest:
        cams = ("exterior_1", "wrist") if self.fmt == "pi0" else ("exterior_1", "exterior_2", "wrist")
        return ObsRequest(cams, 320, 180)

    def spec(self) -> str:
        return f"openpi:{self.address}"

    # ------------------------------------------------------------------ connection
    def _connect(self) -> None:
        from websockets.sync.client import connect

        headers = {"Authorization": f"Api-Key {self.api_key}"} if self.api_key else None
        self.ws = connect(self.uri, compression=None, max_size=None, additional_headers=headers, open_timeout=10)
        self.metadata = unpackb(self.ws.recv(timeout=30))

    def _close(self) -> None:
        if self.ws is not None:
            try:
                self.ws.close()
            except Exception:
                pass
        self.ws = None

    def infer(self, obs: dict) -> dict:
        """One request with reconnect + exponential back-off; raises ``ConnectionError`` after ``max_wait_s``."""
        deadline = time.monotonic() + self.max_wait_s
        delay, last = 0.25, None
        while True:
            try:
                if self.ws is None:
                    self._connect()
                self.ws.send(packb(obs))
                reply = self.ws.recv(timeout=max(self.max_wait_s, 60.0))
                if isinstance(reply, str):  # openpi servers send the traceback as a text frame
                    self._close()
                    raise RuntimeError(f"openpi server error: {reply.strip().splitlines()[-1] if reply.strip() else reply}")
                return unpackb(reply)
            except (OSError, TimeoutError, EOFError) as e:  # connection refused / reset / closed
                last = e
            except Exception as e:  # websockets.ConnectionClosed and friends
                if isinstance(e, RuntimeError) and str(e).startswith("openpi server error"):
                    raise
                last = e
            self._close()
            if time.monotonic() + delay > deadline:
                raise ConnectionError(f"openpi server {self.uri} unreachable for {self.max_wait_s:.0f} s ({type(last).__name__}: {last})")
            time.sleep(delay)
            delay = min(delay * 2, 5.0)

    # ------------------------------------------------------------------ requests
    def request(self, batch: PolicyInput, i: int) -> dict:
        state = batch.state[i].astype(np.float32)
        if self.fmt == "pi0":
            s = self.image_size
            return {
                "observation/exterior_image_1_left": resize_with_pad(batch.images["exterior_1"][i], s, s),
                "observation/wrist_image_left": resize_with_pad(batch.images["wrist"][i], s, s),
                "observation/joint_position": state[:7].astype(np.float64),
                "observation/gripper_position": state[7:8].astype(np.float64),
                "prompt": batch.instructions[i],
            }
        return {
            "video.exterior_image_1": batch.images["exterior_1"][i][None],
            "video.exterior_image_2": batch.images["exterior_2"][i][None],
            "video.wrist_image": batch.images["wrist"][i][None],
            "state.joint_position": state[None, :7].astype(np.float64),
            "state.gripper_position": state[None, 7:8].astype(np.float64),
            "prompt": [batch.instructions[i]],
        }

    @staticmethod
    def parse(reply: dict) -> np.ndarray:
        if "actions" in reply:
            a = np.asarray(reply["actions"], dtype=np.float32)
        elif "action.joint_position" in reply:
            a = np.concatenate([np.asarray(reply["action.joint_position"], np.float32).reshape(-1, 7),
                                np.asarray(reply["action.gripper_position"], np.float32).reshape(-1, 1)], axis=1)
        else:
            raise RuntimeError(f"openpi reply has no 'actions' (keys: {sorted(reply)})")
        if a.ndim == 1:
            a = a[None]
        if a.shape[-1] != 8:
            raise RuntimeError(f"openpi reply actions have shape {a.shape}, expected (T, 8) droid_joint_pos")
        a[:, 7] = np.clip(a[:, 7], 0.0, 1.0)
        return a

    def act(self, batch: PolicyInput) -> PolicyOutput:
        chunks: list[np.ndarray | None] = []
        errors: list[str | None] = []
        for i in range(len(batch)):
            try:
                chunks.append(self.parse(self.infer(self.request(batch, i))))
                errors.append(None)
            except (ConnectionError, RuntimeError) as e:
                chunks.append(None)
                errors.append(str(e))
        t = max((c.shape[0] for c in chunks if c is not None), default=1)
        out = np.repeat(batch.state[:, None, :].astype(np.float32), t, axis=1)  # failed rows: hold
        for i, c in enumerate(chunks):
            if c is not None:
                out[i, : len(c)] = c
                out[i, len(c):] = c[-1]  # shorter chunks: hold their last action
        return PolicyOutput(out, errors if any(errors) else None)

    def close(self) -> None:
        self._close()


def _factory(arg: str | None, **kw) -> OpenPIPolicy:
    if not arg:
        raise ValueError("openpi policy needs an address: openpi:HOST:PORT")
    return OpenPIPolicy(arg, fmt=kw.get("openpi_format") or "pi0", max_wait_s=float(kw.get("openpi_wait_s") or 30.0))


POLICIES.register("openpi", _factory)
