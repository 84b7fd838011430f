"""RoboArena policy servers (``robo-arena/roboarena``, ``roboarena/policy_server.py``) as a policy:
``roboarena:HOST:PORT[,HOST:PORT...]``.

Protocol: on connect the server sends its ``PolicyServerConfig`` (msgpack-numpy map):
``image_resolution`` (H, W) or None, ``needs_wrist_camera``, ``n_external_cameras`` (0-2),
``needs_stereo_camera``, ``needs_session_id``, ``action_space`` (``joint_position`` |
``joint_velocity``); missing fields take the defaults RoboArena's evaluation client uses. Every
request carries ``endpoint``: ``"reset"`` (with ``session_id``; answered by a text frame) at each
episode start, ``"infer"`` with only what the config asks for, as RoboArena's DROID evaluation client
sends it: ``observation/wrist_image_left``, ``observation/exterior_image_{1,2}_left`` (our
``exterior_1`` / ``exterior_2`` cameras, resized with padding to ``image_resolution``; None sends the
env's camera size), ``session_id`` (a new one per episode), ``observation/joint_position`` (7),
``observation/cartesian_position`` (6: flange xyz + euler xyz, DROID's), ``observation/gripper_position``
(1), ``prompt``. The answer is (N, 8): 7 joint actions in the declared space + gripper position,
or ``{"actions": (N, 8)}``; joint velocities are clipped to [-1, 1] as RoboArena's evaluation client
does, the gripper position is clipped to [0, 1] but not binarised at 0.5 as that client does (the
env's gripper follows a position command; a policy that answers 0/1 is unaffected). A server asking for stereo images is refused (realm-ms has no
stereo cameras).

Transport, concurrency, retries, reply validation and error records are ``websocket_client``'s
(shared with openpi). Each episode slot keeps to one connection (slot mod connections), so a server
sees one episode's requests, reset first, on one connection, as on the robot.
"""

from __future__ import annotations

import uuid
from dataclasses import dataclass

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.openpi_wire import resize_with_pad
from realm_ms.eval.policies.policy import ObsRequest, PolicyInput, PolicyOutput
from realm_ms.eval.policies.replies import ReplyError, check_metadata
from realm_ms.eval.policies.websocket_client import ServerPolicy

ACTION_SPACES = ("joint_position", "joint_velocity")


@dataclass(frozen=True)
class RoboArenaConfig:
    """A server's ``PolicyServerConfig``, validated."""

    image_resolution: tuple[int, int] | None = (224, 224)
    needs_wrist_camera: bool = True
    n_external_cameras: int = 1
    needs_stereo_camera: bool = False
    needs_session_id: bool = False
    action_space: str = "joint_position"

    @classmethod
    def parse(cls, meta, source: str) -> "RoboArenaConfig":
        meta = check_metadata(meta, source)

        def flag(key: str, default: bool) -> bool:
            v = meta.get(key, default)
            if not isinstance(v, (bool, np.bool_)):
                raise ReplyError(f"{source}: its config's {key} is {v!r}; expected true or false")
            return bool(v)

        res = meta.get("image_resolution")
        if res is not None:
            ok = isinstance(res, (list, tuple, np.ndarray)) and len(res) == 2 and all(
                isinstance(x, (int, np.integer)) and not isinstance(x, bool) and 8 <= int(x) <= 4096 for x in res)
            if not ok:
                raise ReplyError(f"{source}: its config's image_resolution is {res!r}; expected (H, W) with sizes in [8, 4096], or null")
            res = (int(res[0]), int(res[1]))
        n_ext = meta.get("n_external_cameras", 1)
        if isinstance(n_ext, bool) or not isinstance(n_ext, (int, np.integer)) or not 0 <= int(n_ext) <= 2:
            raise ReplyError(f"{source}: its config's n_external_cameras is {n_ext!r}; expected 0, 1 or 2")
        space = meta.get("action_space", "joint_position")
        if not isinstance(space, str) or space not in ACTION_SPACES:
            raise ReplyError(f"{source}: its config declares action_space {space!r}; RoboArena servers use {' or '.join(ACTION_SPACES)}")
        cfg = cls(res, flag("needs_wrist_camera", True), int(n_ext), flag("needs_stereo_camera", False), flag("needs_session_id", False), space)
        if cfg.needs_stereo_camera:
            raise ReplyError(f"{source}: its config asks for stereo images (needs_stereo_camera: true); realm-ms has no stereo cameras, "
                             "serve the policy with needs_stereo_camera false")
        return cfg

    def cameras(self) -> tuple[str, ...]:
        return tuple(f"exterior_{k}" for k in range(1, self.n_external_cameras + 1)) + (("wrist",) if self.needs_wrist_camera else ())

    def env_action_space(self) -> dict:
        return {} if self.action_space == "joint_position" else {"action_space": "joint_velocity", "gripper_action_space": "position"}


def _reset_ok(text: str) -> bool:
    return not text.lstrip().startswith("Traceback")  # RoboArena answers a reset with a text frame; an error is a traceback


class RoboArenaPolicy(ServerPolicy):
    name = "roboarena"
    text_ok = None

    def __init__(self, address: str, max_wait_s: float = 30.0, connections: int = 1, max_in_flight: int | None = None,
                 action_space: str | None = None, reply_timeout_s: float | None = None):
        """Connects to the first server now: its config decides the cameras and the action space.
        ``ConnectionError`` when it stays unreachable, ``ValueError`` for a config realm-ms cannot
        serve (stereo) or a bad one, or an ``action_space`` option the config contradicts."""
        from realm_ms.agents.droid_action_spaces import parse_action_space_flag

        self.config: RoboArenaConfig | None = None
        try:
            wanted = parse_action_space_flag(action_space) if action_space else None
        except ValueError as e:
            raise ValueError(f"--action-space: {e}") from None
        super().__init__(address, max_wait_s, connections, max_in_flight, reply_timeout_s)
        try:
            self.conns[0].connect()
        except ReplyError as e:
            raise ValueError(str(e)) from None
        if action_space:
            if wanted != self.config.env_action_space():
                raise ValueError(f"--action-space {action_space}: {self.conns[0].source} declares action_space {self.config.action_space} "
                                 "(a RoboArena server chooses its action space); drop --action-space")
        self.sessions: dict[int, str] = {}
        self.failed: dict[int, str] = {}  # slot -> why its episode's reset failed
        self._ik = None
        self._poses = None

    def check_metadata(self, meta, source: str) -> dict:
        cfg = RoboArenaConfig.parse(meta, source)
        if self.config is None:
            self.config = cfg
        elif cfg != self.config:
            raise ReplyError(f"{source}: its config {cfg} differs from the first server's {self.config}; serve one policy behind one spec")
        return meta

    def obs_request(self) -> ObsRequest:
        return ObsRequest(self.config.cameras(), 320, 180)

    def env_action_space(self) -> dict:
        return self.config.env_action_space()

    def space_known(self) -> bool:
        return True

    # ------------------------------------------------------------------ episodes
    def pinned(self, batch: PolicyInput) -> list[int]:
        return list(batch.slots) if batch.slots else list(range(len(batch)))

    def reset(self, slots: list[int]) -> None:
        """A new session per starting slot, announced with ``endpoint: reset`` on the slot's connection;
        a failed reset fails that episode at its first request."""
        for s in slots:
            self.sessions[s] = f"realm-{uuid.uuid4().hex[:16]}"
            self.failed.pop(s, None)

        def work(conn, i):
            return conn.exchange({"session_id": self.sessions[slots[i]], "endpoint": "reset"}, _reset_ok)

        for s, (_, err, _, _) in zip(slots, self.pool.run(len(slots), work, list(slots))):
            if err:
                self.failed[s] = f"reset: {err}"

    def act(self, batch: PolicyInput) -> PolicyOutput:
        if self._ik is None:
            from realm_ms.agents.droid_action_spaces import DroidIK

            self._ik = DroidIK()
        self._poses = self._ik.pose(batch.state[:, :7].astype(np.float64))  # one batched FK per round
        return super().act(batch)

    def request(self, batch: PolicyInput, i: int) -> dict:
        cfg, state = self.config, batch.state[i].astype(np.float64)
        slot = batch.slots[i] if batch.slots else i
        if slot in self.failed:  # its episode's reset failed: nothing is sent, the episode fails
            raise ReplyError(self.failed[slot])
        obs: dict = {}

        def image(cam: str) -> np.ndarray:
            img = batch.images[cam][i]
            return img if cfg.image_resolution is None else resize_with_pad(img, *cfg.image_resolution)

        if cfg.needs_wrist_camera:
            obs["observation/wrist_image_left"] = image("wrist")
        for k in range(1, cfg.n_external_cameras + 1):
            obs[f"observation/exterior_image_{k}_left"] = image(f"exterior_{k}")
        if cfg.needs_session_id:
            obs["session_id"] = self.sessions.setdefault(slot, f"realm-{uuid.uuid4().hex[:16]}")
        obs["observation/joint_position"] = state[:7]
        obs["observation/cartesian_position"] = self._poses[i]
        obs["observation/gripper_position"] = state[7:8]
        obs["prompt"] = batch.instructions[i]
        obs["endpoint"] = "infer"
        return obs

    def actions(self, reply, source: str):
        if isinstance(reply, dict):
            if "actions" not in reply:
                raise ReplyError(f"{source}: its reply is a map without 'actions' (keys: {sorted(map(str, reply))[:8]}); expected an (N, 8) array")
            return reply["actions"]
        return reply

    def postprocess(self, chunk: np.ndarray, space) -> np.ndarray:
        """Gripper position clipped to [0, 1]; joint velocities clipped to [-1, 1], as RoboArena's evaluation client."""
        chunk = super().postprocess(chunk, space)
        if self.config.action_space == "joint_velocity":
            chunk[:, :7] = np.clip(chunk[:, :7], -1.0, 1.0)
        return chunk


def _factory(arg: str | None, **kw) -> RoboArenaPolicy:
    if not arg:
        raise ValueError("roboarena policy needs an address: roboarena:HOST:PORT[,HOST:PORT...]")
    return RoboArenaPolicy(arg, max_wait_s=float(kw.get("openpi_wait_s") or 30.0), connections=int(kw.get("openpi_connections") or 1),
                           max_in_flight=kw.get("openpi_max_in_flight"), action_space=kw.get("action_space"))


POLICIES.register("roboarena", _factory)
