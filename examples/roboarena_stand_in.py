"""A RoboArena policy server to point ``realm eval`` at: RoboArena's protocol with a toy policy.

    python examples/roboarena_stand_in.py [--port 8000] [--latency 0.3] [--action-space joint_position]

Your own policy is served the same way with RoboArena's ``WebsocketPolicyServer`` (``pip install``
``robo-arena/roboarena``): a class with ``infer(obs) -> (N, 8)`` and ``reset(info)``, and a
``PolicyServerConfig``. Here realm-ms's stand-in server (same handshake and frames) serves a toy
policy that nudges joint 0 towards +0.5 rad and holds the gripper open, after sleeping ``--latency``
seconds as a VLA would think.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


class NudgePolicy:
    def __init__(self, latency: float, velocity: bool):
        self.latency, self.velocity = latency, velocity

    def reset(self, info: dict) -> None:
        print(f"reset: session {info.get('session_id')}", flush=True)

    def infer(self, obs: dict) -> np.ndarray:
        time.sleep(self.latency)
        q = np.asarray(obs["observation/joint_position"], np.float64)
        step = np.clip(0.5 - q[0], -0.05, 0.05)
        if self.velocity:  # joint velocities in [-1, 1] (DROID: 1 = 0.2 rad per step)
            a = np.zeros((8, 8))
            a[:, 0] = step / 0.2
            return a
        a = np.tile(np.append(q, 0.0), (8, 1))
        a[:, 0] = q[0] + step * np.arange(1, 9)
        return a


def main() -> None:
    from realm_ms.eval.policies.roboarena_server import RoboArenaServer

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, default=8000)
    ap.add_argument("--latency", type=float, default=0.3, help="seconds the toy policy 'thinks' per request")
    ap.add_argument("--action-space", choices=("joint_position", "joint_velocity"), default="joint_position")
    args = ap.parse_args()
    config = dict(image_resolution=(224, 224), needs_wrist_camera=True, n_external_cameras=1, needs_stereo_camera=False,
                  needs_session_id=True, action_space=args.action_space)
    srv = RoboArenaServer(NudgePolicy(args.latency, args.action_space == "joint_velocity"), config, port=args.port, serial=True).start()
    print(f"serving RoboArena's protocol on {srv.address} (Ctrl-C stops)", flush=True)
    try:
        while True:
            time.sleep(1)
    except KeyboardInterrupt:
        srv.stop()


if __name__ == "__main__":
    main()
