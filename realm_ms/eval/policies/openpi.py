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

Serving, retries, error records and reply validation are ``websocket_client``'s (shared with the
RoboArena client): ``openpi:HOST:PORT[,HOST:PORT...]`` names one or more servers, every row of a
round is in flight at once on a free connection, a server that stays down fails the episodes of
that round, never the run. An openpi server answers one request at a time (its handler calls the
model synchronously), so rows spread over N servers are served about N times faster
(``bench/openpi_throughput.py``).

Action spaces: replies are actions of the env's DROID action space (``--action-space``, or the
server metadata's ``action_space`` / ``gripper_action_space``; pi0-FAST-DROID and pi0.5-DROID
answer ``joint_velocity`` + gripper ``position``, openpi ``examples/droid/main.py``): (T, 8) for the
joint spaces, (T, 7) for the Cartesian ones.
"""

from __future__ import annotations

import numpy as np

from realm_ms.eval.policies import POLICIES
from realm_ms.eval.policies.openpi_wire import resize_with_pad
from realm_ms.eval.policies.policy import CAMERAS, ObsRequest, PolicyInput
from realm_ms.eval.policies.replies import ReplyError, metadata_action_space
from realm_ms.eval.policies.websocket_client import ServerPolicy, ServerUnreachable

FORMATS = ("pi0", "groot")


class OpenPIPolicy(ServerPolicy):
    name = "openpi"

    def __init__(self, address: str, fmt: str = "pi0", max_wait_s: float = 30.0, api_key: str | None = None, image_size: int = 224,
                 connections: int = 1, max_in_flight: int | None = None, action_space: str | None = None,
                 reply_timeout_s: float | None = None):
        """``address``: ``HOST:PORT[,HOST:PORT...]``; ``connections`` websockets per server; at most
        ``max_in_flight`` requests outstanding (default: every connection busy); ``action_space``:
        the env's DROID action space (``SPACE[:GRIPPER]``), else what the server's metadata declares."""
        if fmt not in FORMATS:
            raise ValueError(f"unknown openpi request format {fmt!r}; known: {', '.join(FORMATS)}")
        if action_space:
            from realm_ms.agents.droid_action_spaces import parse_action_space_flag

            try:
                parse_action_space_flag(action_space)
            except ValueError as e:
                raise ValueError(f"--action-space: {e}") from None
        super().__init__(address, max_wait_s, connections, max_in_flight, reply_timeout_s, api_key)
        self.fmt, self.api_key, self.image_size = fmt, api_key, image_size
        self.action_space_flag = action_space

    def obs_request(self) -> ObsRequest:
        cams = ("exterior_1", "wrist") if self.fmt == "pi0" else CAMERAS
        return ObsRequest(cams, 320, 180)

    # ------------------------------------------------------------------ action space
    def check_metadata(self, meta, source: str) -> dict:
        meta = super().check_metadata(meta, source)
        if not self.action_space_flag:
            metadata_action_space(meta, source)  # a bogus declaration names the server, not a flag
        return meta

    def space_known(self) -> bool:
        return bool(self.action_space_flag) or self.pool.metadata is not None

    def env_action_space(self) -> dict:
        """Env keywords of the action space this policy acts in: the ``action_space`` option, else
        the server metadata's ``action_space`` / ``gripper_action_space`` (read by connecting to
        the first server), else ``{}`` (joint_position). A server that is down now gives ``{}``
        (rounds retry and record errors as usual); one whose metadata is bad raises ``ReplyError``."""
        from realm_ms.agents.droid_action_spaces import parse_action_space_flag

        if self.action_space_flag:
            return parse_action_space_flag(self.action_space_flag)
        if self.pool.metadata is None:
            try:
                self.conns[0].connect()
            except ServerUnreachable:
                return {}
        return metadata_action_space(self.metadata, self.conns[0].source if self.conns[0].metadata is not None else "openpi server")

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

    def actions(self, reply, source: str):
        """The raw actions of a reply: ``actions``, or GR00T's ``action.joint_position`` + ``action.gripper_position``."""
        if not isinstance(reply, dict):
            raise ReplyError(f"{source}: its reply is a {type(reply).__name__}, not a map with 'actions'")
        if "actions" in reply:
            return reply["actions"]
        if "action.joint_position" in reply and "action.gripper_position" in reply:
            try:
                j = np.asarray(reply["action.joint_position"], np.float64).reshape(-1, 7)
                g = np.asarray(reply["action.gripper_position"], np.float64).reshape(-1, 1)
                return np.concatenate([j, g], axis=1)
            except (TypeError, ValueError) as e:
                raise ReplyError(f"{source}: its GR00T-format actions do not form (T, 7) joints + (T, 1) gripper ({e})") from None
        raise ReplyError(f"{source}: its reply has no 'actions' (keys: {sorted(map(str, reply))[:8]})")


def _factory(arg: str | None, **kw) -> OpenPIPolicy:
    if not arg:
        raise ValueError("openpi policy needs an address: openpi:HOST:PORT[,HOST:PORT...]")
    return OpenPIPolicy(arg, fmt=kw.get("openpi_format") or "pi0", max_wait_s=float(kw.get("openpi_wait_s") or 30.0),
                        connections=int(kw.get("openpi_connections") or 1), max_in_flight=kw.get("openpi_max_in_flight"),
                        action_space=kw.get("action_space"))


POLICIES.register("openpi", _factory)
