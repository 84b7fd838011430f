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

Serving: ``openpi:HOST:PORT[,HOST:PORT...]`` names one or more servers; the policy keeps
``connections`` websockets per server and sends every row of a round at once, each on a free
connection (at most ``max_in_flight`` outstanding), and returns the chunks in row (slot) order. An
openpi server answers one request at a time (its handler calls the model synchronously), so rows
spread over N servers are served about N times faster (``bench/openpi_throughput.py``).

A lost connection is retried with exponential back-off for up to ``max_wait_s``; a server that stays
down fails the episodes of that round (``PolicyOutput.errors``), never the run, and the next round
tries again.

Action spaces: replies are actions of the env's DROID action space (``--action-space``, or the
server metadata's ``action_space`` / ``gripper_action_space``; pi0-FAST-DROID and pi0.5-DROID
answer ``joint_velocity`` + gripper ``position``, openpi ``examples/droid/main.py``): (T, 8) for the
joint spaces, (T, 7) for the Cartesian ones.
"""

from __future__ import annotations

import time

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.policy import CAMERAS, ObsRequest, Policy, PolicyInput, PolicyOutput
from realm_ms.eval.policies.openpi_wire import packb, resize_with_pad, unpackb

FORMATS = ("pi0", "groot")


class Connection:
    """One websocket to one server, with openpi's reconnect + exponential back-off."""

    def __init__(self, address: str, max_wait_s: float, api_key: str | None = None):
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise ValueError(f"openpi policy needs HOST:PORT, got {address!r}")
        from realm_ms.validate import check_port, check_positive

        check_port(port, f"openpi:{address}: port")  # 99999 would be retried until the wait ends
        check_positive(max_wait_s, "--openpi-wait", "s")  # a NaN deadline never passes: a hang
        self.address, self.max_wait_s, self.api_key = address, max_wait_s, api_key
        self.uri = address if address.startswith("ws") else f"ws://{host}:{port}"
        self.ws = None
        self.metadata: dict | None = None

    def _connect(self) -> None:
        from websockets.sync.client import connect

        headers = {"Authorization": f"Api-Key {self.api_key}"} if self.api_key else None
        self.ws = connect(self.uri, compression=None, max_size=None, additional_headers=headers, open_timeout=10)
        self.metadata = unpackb(self.ws.recv(timeout=30))

    def close(self) -> None:
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
                    self.close()
                    raise RuntimeError(f"openpi server error: {reply.strip().splitlines()[-1] if reply.strip() else reply}")
                return unpackb(reply)
            except (OSError, TimeoutError, EOFError) as e:  # connection refused / reset / closed
                last = e
            except Exception as e:  # websockets.ConnectionClosed and friends
                if isinstance(e, RuntimeError) and str(e).startswith("openpi server error"):
                    raise
                last = e
            self.close()
            if time.monotonic() + delay > deadline:
                raise ConnectionError(f"openpi server {self.uri} unreachable for {self.max_wait_s:.0f} s ({type(last).__name__}: {last})")
            time.sleep(delay)
            delay = min(delay * 2, 5.0)


class OpenPIPolicy(Policy):
    name = "openpi"

    def __init__(self, address: str, fmt: str = "pi0", max_wait_s: float = 30.0, api_key: str | None = None, image_size: int = 224,
                 connections: int = 1, max_in_flight: int | None = None, action_space: str | None = None):
        """``address``: ``HOST:PORT[,HOST:PORT...]``; ``connections`` websockets per server; at most
        ``max_in_flight`` requests outstanding (default: every connection busy); ``action_space``:
        the env's DROID action space (``SPACE[:GRIPPER]``), else what the server's metadata declares."""
        if fmt not in FORMATS:
            raise ValueError(f"unknown openpi request format {fmt!r}; known: {', '.join(FORMATS)}")
        addresses = [a.strip() for a in address.split(",") if a.strip()]
        if not addresses:
            raise ValueError(f"openpi policy needs HOST:PORT[,HOST:PORT...], got {address!r}")
        if connections < 1:
            raise ValueError(f"openpi connections per server must be >= 1, got {connections}")
        # round-robin over servers, so a partial pool still spreads over every server
        self.conns = [Connection(a, max_wait_s, api_key) for _ in range(connections) for a in addresses]
        self.max_in_flight = max(1, min(max_in_flight or len(self.conns), len(self.conns)))
        self.address, self.fmt, self.max_wait_s, self.api_key, self.image_size = ",".join(addresses), fmt, max_wait_s, api_key, image_size
        self.connections = connections
        self.action_space_flag = action_space
        self._pool = None  # ThreadPoolExecutor, made on the first concurrent round

    @property
    def uri(self) -> str:
        return self.conns[0].uri

    @property
    def metadata(self) -> dict:
        return next((c.metadata for c in self.conns if c.metadata is not None), {})

    def obs_request(self) -> ObsRequest:
        cams = ("exterior_1", "wrist") if self.fmt == "pi0" else CAMERAS
        return ObsRequest(cams, 320, 180)

    def spec(self) -> str:
        return f"openpi:{self.address}"

    def infer(self, obs: dict) -> dict:
        """One request on the first connection (sequential use, tests)."""
        return self.conns[0].infer(obs)

    def _close(self) -> None:
        for c in self.conns:
            c.close()

    # ------------------------------------------------------------------ action space
    def env_action_space(self) -> dict:
        """Env keywords of the action space this policy acts in: the ``action_space`` option, else
        the server metadata's ``action_space`` / ``gripper_action_space`` (read by connecting to
        the first server), else ``{}`` (joint_position)."""
        from realm_ms.agents.droid_action_spaces import parse_action_space_flag

        if self.action_space_flag:
            return parse_action_space_flag(self.action_space_flag)
        if self.conns[0].metadata is None:
            try:
                self.conns[0]._connect()
            except Exception:
                return {}  # unreachable now: rounds retry and record errors as usual
        meta = self.metadata
        if not meta.get("action_space"):
            return {}
        grip = meta.get("gripper_action_space")
        return parse_action_space_flag(f"{meta['action_space']}:{grip}" if grip else meta["action_space"])

    def _space(self):
        """(DroidActionSpace, DroidIK | None) of the replies: fixed once a server's metadata was read."""
        from realm_ms.agents.droid_action_spaces import DroidIK, make_action_space

        if getattr(self, "_space_cache", None) is None:
            kw = self.env_action_space()
            space = make_action_space(kw.get("action_space", "joint_position"), kw.get("gripper_action_space"))
            ik = DroidIK() if space.action_space.startswith("cartesian") else None
            if self.action_space_flag or self.conns[0].metadata is not None:
                self._space_cache = (space, ik)
            return space, ik
        return self._space_cache

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
    def parse(reply: dict, dim: int = 8, gripper: str = "position") -> np.ndarray:
        """(T, dim) actions of a reply; a ``position`` gripper is clipped to [0, 1]."""
        if "actions" in reply:
            a = np.array(reply["actions"], dtype=np.float32)
        elif "action.joint_position" in reply:
            a = np.concatenate([np.asarray(reply["action.joint_position"], np.float32).reshape(-1, 7),
                                np.asarray(reply["action.gripper_position"], np.float32).reshape(-1, 1)], axis=1)
        else:
            raise RuntimeError(f"openpi reply has no 'actions' (keys: {sorted(reply)})")
        if a.ndim == 1:
            a = a[None]
        if a.shape[-1] != dim:
            raise RuntimeError(f"openpi reply actions have shape {a.shape}, expected (T, {dim}) for the env's action space "
                               f"(joint spaces: 8, Cartesian: 7; set it with --action-space or the server metadata)")
        if gripper == "position":
            a[:, -1] = np.clip(a[:, -1], 0.0, 1.0)
        return a

    def _serve(self, conn: Connection, batch: PolicyInput, i: int) -> tuple[np.ndarray | None, str | None]:
        try:
            return self.parse(conn.infer(self.request(batch, i)), *self._parse_args), None
        except (ConnectionError, RuntimeError) as e:
            return None, str(e)

    def act(self, batch: PolicyInput) -> PolicyOutput:
        """Every row's request in flight at once over the connection pool (at most ``max_in_flight``);
        results in row order; a row whose server stays down (or errs) gets an error, others are served."""
        space, ik = self._space()
        self._parse_args = (space.dim, space.gripper)
        n = len(batch)
        if self.max_in_flight == 1 or n == 1:
            results = [self._serve(self.conns[0], batch, i) for i in range(n)]
        else:
            import queue
            from concurrent.futures import ThreadPoolExecutor

            if self._pool is None:
                self._pool = ThreadPoolExecutor(self.max_in_flight, thread_name_prefix="openpi")
            idle: queue.SimpleQueue = queue.SimpleQueue()
            for c in self.conns[: self.max_in_flight]:
                idle.put(c)

            def one(i: int):
                conn = idle.get()  # a free connection: bounds the requests in flight
                try:
                    return self._serve(conn, batch, i)
                finally:
                    idle.put(conn)

            results = list(self._pool.map(one, range(n)))
        chunks = [c for c, _ in results]
        errors = [e for _, e in results]
        t = max((c.shape[0] for c in chunks if c is not None), default=1)
        q, g = batch.state[:, :7], batch.state[:, 7]
        hold = space.hold(q, g, ik).astype(np.float32)  # failed rows: keep still, in the env's action space
        out = np.repeat(hold[:, None, :], t, axis=1)
        for i, c in enumerate(chunks):
            if c is not None:
                out[i, : len(c)] = c
                out[i, len(c):] = c[-1]  # shorter chunks: hold their last action
        return PolicyOutput(out, errors if any(errors) else None)

    def close(self) -> None:
        self._close()
        if self._pool is not None:
            self._pool.shutdown(wait=False)
            self._pool = None


def _factory(arg: str | None, **kw) -> OpenPIPolicy:
    if not arg:
        raise ValueError("openpi policy needs an address: openpi:HOST:PORT[,HOST:PORT...]")
    return OpenPIPolicy(arg, fmt=kw.get("openpi_format") or "pi0", max_wait_s=float(kw.get("openpi_wait_s") or 30.0),
                        connections=int(kw.get("openpi_connections") or 1), max_in_flight=kw.get("openpi_max_in_flight"),
                        action_space=kw.get("action_space"))


POLICIES.register("openpi", _factory)
