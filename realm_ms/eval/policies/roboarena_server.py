"""A stand-in RoboArena policy server (in-process, threaded), written from RoboArena's protocol
(``robo-arena/roboarena``, ``roboarena/policy_server.py``): on connect it sends its
``PolicyServerConfig`` as a msgpack-numpy map; every request carries ``endpoint``: ``"reset"`` is
answered with the text frame ``"reset successful"``, ``"infer"`` with the packed (N, 8) action
array; a failing policy sends its traceback as a text frame and closes with an internal-error code.

For tests, the policy-author docs and the throughput bench. ``policy``: an object with
``infer(obs) -> (N, 8)`` and optionally ``reset(info)``, or an ``infer`` callable (with an optional
``reset``, e.g. ``openpi_server.ReplayInfer``).
"""

from __future__ import annotations

from realm_ms.eval.policies.openpi_server import OpenPIServer
from realm_ms.eval.policies.openpi_wire import packb

# RoboArena's PolicyServerConfig defaults
DEFAULT_CONFIG = dict(image_resolution=(224, 224), needs_wrist_camera=True, n_external_cameras=1, needs_stereo_camera=False,
                      needs_session_id=False, action_space="joint_position")


class RoboArenaServer(OpenPIServer):
    def __init__(self, policy, config: dict | None = None, host: str = "127.0.0.1", port: int = 0, serial: bool = False):
        infer = policy if callable(policy) and not hasattr(policy, "infer") else policy.infer
        metadata = config if config is not None and not isinstance(config, dict) else DEFAULT_CONFIG | (config or {})
        super().__init__(infer, host, port, metadata=metadata, serial=serial)
        self.policy = policy
        self.resets: list[dict] = []  # every reset's info, in order
        self.seen: list[dict] = []  # every infer request's observation, in order

    def answer(self, obs: dict) -> bytes | str:
        endpoint = obs.pop("endpoint")  # a request without one fails, as RoboArena's server does
        if endpoint == "reset":
            self.resets.append(obs)
            if hasattr(self.policy, "reset"):
                self.policy.reset(obs)
            return "reset successful"
        self.seen.append(obs)
        action = self.infer(obs)
        self.requests += 1
        return action if isinstance(action, (bytes, str)) else packb(action)
