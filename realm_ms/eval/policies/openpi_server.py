"""A minimal openpi-protocol websocket server (in-process, threaded): for tests and for serving any
callable ``infer(obs: dict) -> dict`` to openpi clients (same handshake and framing as openpi's
``WebsocketPolicyServer``: metadata first, one binary reply per request, errors as a text frame).

``serial=True`` answers one request at a time over all connections, as openpi's server does (its
asyncio handler calls the model synchronously): the stand-in for one GPU server in the throughput
bench.

``infer`` may return ``bytes`` or ``str`` to send a frame as it is (tests of broken servers).
``RoboArenaServer`` (``roboarena_server.py``) is this server with RoboArena's endpoints."""

from __future__ import annotations

import threading
import traceback
from collections.abc import Callable

from realm_ms.eval.policies.openpi_wire import packb, unpackb


class OpenPIServer:
    def __init__(self, infer: Callable[[dict], dict], host: str = "127.0.0.1", port: int = 0, metadata: dict | None = None,
                 serial: bool = False):
        self.infer, self.host, self.port = infer, host, port
        self.metadata = {} if metadata is None else metadata
        self.requests = 0
        self._lock = threading.Lock() if serial else None
        self._server = None
        self._thread = None

    def answer(self, obs: dict) -> bytes | str:
        """The frame answering one request (openpi: the packed ``infer(obs)``)."""
        reply = self.infer(obs)
        self.requests += 1
        return reply if isinstance(reply, (bytes, str)) else packb(reply)

    def _handle(self, ws) -> None:
        ws.send(self.metadata if isinstance(self.metadata, (bytes, str)) else packb(self.metadata))
        while True:
            try:
                msg = ws.recv()
            except Exception:
                return  # client went away
            try:
                if self._lock is not None:
                    with self._lock:
                        reply = self.answer(unpackb(msg))
                else:
                    reply = self.answer(unpackb(msg))
                ws.send(reply)
            except Exception:
                # as openpi's and RoboArena's servers: the traceback as a text frame, then close
                # with an internal-error code
                try:
                    ws.send(traceback.format_exc())
                    ws.close(code=1011, reason="Internal server error. Traceback included in previous frame.")
                except Exception:
                    pass
                return

    def start(self) -> "OpenPIServer":
        from websockets.sync.server import serve

        self._server = serve(self._handle, self.host, self.port, compression=None, max_size=None)
        self.port = self._server.socket.getsockname()[1]
        self._thread = threading.Thread(target=self._server.serve_forever, daemon=True)
        self._thread.start()
        return self

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    def stop(self) -> None:
        if self._server is not None:
            self._server.shutdown()
            self._thread.join(timeout=5)
            self._server = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()


def hold_infer(obs: dict, horizon: int = 10) -> dict:
    """A pi0-format server body that answers "hold the current joints, open gripper" (tests, smoke runs)."""
    import numpy as np

    q = np.asarray(obs["observation/joint_position"], dtype=np.float64).reshape(7)
    a = np.concatenate([np.tile(q, (horizon, 1)), np.zeros((horizon, 1))], axis=1)
    return {"actions": a}


def sleep_infer(obs: dict, seconds: float = 0.1, horizon: int = 10) -> dict:
    """A pi0-format stand-in for a model: sleeps ``seconds`` (the inference time), answers
    ``horizon`` zero joint velocities with the gripper held (throughput bench)."""
    import time

    import numpy as np

    time.sleep(seconds)
    g = float(np.asarray(obs["observation/gripper_position"]).reshape(-1)[0])
    return {"actions": np.concatenate([np.zeros((horizon, 7)), np.full((horizon, 1), g)], axis=1)}


class ReplayInfer:
    """Serves a recorded action sequence in chunks of ``chunk``, one chunk per request, in order
    (tests: a server answering an expert's recorded actions); ``reset`` (RoboArena's endpoint)
    starts it again."""

    def __init__(self, actions, chunk: int = 8):
        import numpy as np

        self.actions, self.chunk, self.k = np.asarray(actions, dtype=np.float64), chunk, 0

    def reset(self, info: dict | None = None) -> None:
        self.k = 0

    def __call__(self, obs: dict) -> dict:
        a = self.actions[self.k: self.k + self.chunk]
        if len(a) == 0:
            a = self.actions[-1:]
        self.k += self.chunk
        return {"actions": a}


def expert_actions(task: str = "REALM-PickApple-v1", seed: int = 0, max_steps: int = 300, **env_kwargs):
    """The scripted expert's actions for one successful episode (state observations), in the action
    space ``env_kwargs`` name: what a stand-in server replays (tests, docs). Raises ``RuntimeError``
    if the expert does not succeed within ``max_steps``."""
    import gymnasium as gym
    import numpy as np

    import realm_ms  # noqa: F401  (registers the envs)
    from realm_ms.expert.core import start_episode

    env = gym.make(task, obs_mode="state", **env_kwargs)
    try:
        obs, expert = start_episode(env, seed=seed)
        actions, info = [], {}
        for _ in range(max_steps):
            a = expert.act(obs)
            actions.append(a[0].numpy())
            obs, _, term, trunc, info = env.step(a)
            if bool(term[0]) or bool(trunc[0]):
                break
    finally:
        env.close()
    if not bool(info.get("success", [False])[0]):
        raise RuntimeError(f"the expert did not succeed in {task} seed {seed} within {max_steps} steps")
    return np.stack(actions)
