"""Control steps per second of REALM-PickApple-v1 next to ManiSkill's PickCube-v1, same run, same machine.

Modes: state obs (the default exact law: model terms along the predicted path, one batched
evaluation per action; ``state_physics`` with the terms taken every physics step, ``state_fastctrl``
once per control step, ``state_implicit`` with the former implicit-damping integrator instead of the
step-exact one); 3 raster cameras at 224x224; 3 ray-traced (rt-fast) cameras at 128x128. PickCube
gets the same observation mode with its one camera at the same size/shader, so the ratio shows the
cost of our robot (8 physics substeps of torque control, a 13-DoF gripper linkage, 3 cameras).
With CUDA, also physx_cuda throughput for 64..1024 parallel envs (state obs).

    python bench/step_rate.py [--steps 200] [--modes state,raster224,rt128] [--gpu-envs 64,256,1024]

Prints a table and writes outputs/bench/step_rate.json.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gymnasium as gym
import torch

import realm_ms  # noqa: F401

MODES = {
    "state": dict(obs_mode="state"),
    # same, with the controller's model terms taken at the measured state every physics step
    "state_physics": dict(obs_mode="state", droid_control=dict(model_rate="physics")),
    # same, with the controller's model terms refreshed per control step (DroidControlConfig.model_rate)
    "state_fastctrl": dict(obs_mode="state", droid_control=dict(model_rate="control")),
    # the former integrator (damping on PhysX's implicit drive): what the step-exact default replaced
    "state_implicit": dict(obs_mode="state", droid_control=dict(integrator="implicit_damping")),
    "raster224": dict(obs_mode="rgb", size=224, shader="default"),
    "rt128": dict(obs_mode="rgb", size=128, shader="rt-fast"),
}


def make(env_id: str, mode: str, num_envs: int = 1, backend: str = "physx_cpu"):
    m = MODES[mode]
    kw = dict(obs_mode=m["obs_mode"], num_envs=num_envs, sim_backend=backend)
    if "size" in m:
        if env_id.startswith("REALM"):
            kw.update(camera_width=m["size"], camera_height=m["size"], shader=m["shader"])
        else:
            kw.update(sensor_configs=dict(width=m["size"], height=m["size"], shader_pack=m["shader"]))
    if env_id.startswith("REALM"):
        kw["control_mode"] = "droid_joint_pos"
        if "droid_control" in m:
            kw["droid_control"] = m["droid_control"]
    return gym.make(env_id, **kw)


def rate(env, steps: int) -> float:
    env.reset(seed=0)
    u = env.unwrapped
    if hasattr(u.agent, "arm_qpos"):  # hold the pose with small motions (REALM absolute targets)
        base = torch.cat([u.agent.arm_qpos, torch.zeros(u.num_envs, 1, device=u.device)], dim=1)
        actions = [base + 0.02 * torch.sin(torch.tensor(i / 10.0)) for i in range(steps)]
    else:
        actions = [torch.zeros(env.action_space.shape, device=u.device) for _ in range(steps)]
    for a in actions[:5]:  # warm-up (shader compilation, first contacts)
        env.step(a)
    if u.device.type == "cuda":
        torch.cuda.synchronize()
    t = time.perf_counter()
    for a in actions:
        env.step(a)
    if u.device.type == "cuda":
        torch.cuda.synchronize()
    return steps * u.num_envs / (time.perf_counter() - t)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--modes", default="state,state_physics,state_fastctrl,state_implicit,raster224,rt128")
    p.add_argument("--gpu-envs", default="64,256,1024")
    p.add_argument("--out", type=Path, default=Path("outputs/bench/step_rate.json"))
    args = p.parse_args()
    from realm_ms.validate import output_arg

    output_arg(p, args.out, example="step_rate.json")

    rows = []
    for mode in args.modes.split(","):
        n = args.steps if mode.startswith("state") else max(10, args.steps // (10 if mode == "raster224" else 40))
        r = {}
        for env_id in ("REALM-PickApple-v1", "PickCube-v1"):
            env = make(env_id, mode)
            r[env_id] = rate(env, n)
            env.close()
        rows.append(dict(mode=mode, backend="physx_cpu", num_envs=1, steps=n, realm=r["REALM-PickApple-v1"], pickcube=r["PickCube-v1"]))
        print(f"{mode:>14}: REALM-PickApple {r['REALM-PickApple-v1']:8.1f} steps/s | PickCube {r['PickCube-v1']:8.1f} steps/s | ratio {r['REALM-PickApple-v1'] / r['PickCube-v1']:.2f}x", flush=True)

    if torch.cuda.is_available():
        for n_envs in [int(x) for x in args.gpu_envs.split(",")]:
            r = {}
            for env_id in ("REALM-PickApple-v1", "PickCube-v1"):
                env = make(env_id, "state", n_envs, "physx_cuda")
                r[env_id] = rate(env, 100)
                env.close()
            rows.append(dict(mode="state", backend="physx_cuda", num_envs=n_envs, steps=100, realm=r["REALM-PickApple-v1"], pickcube=r["PickCube-v1"]))
            print(f"physx_cuda x{n_envs:5d}: REALM {r['REALM-PickApple-v1']:10.0f} env-steps/s | PickCube {r['PickCube-v1']:10.0f} | ratio {r['REALM-PickApple-v1'] / r['PickCube-v1']:.2f}x", flush=True)
    else:
        print("no CUDA device: physx_cuda rows skipped")

    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(rows, indent=2))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
