"""Child process of ``realm_ms.rendering.probe_denoiser``: run as a script (imports only sapien).

Renders a box on a plane at 48x32, 2 spp, path depth 2, with the denoiser off and then with
``argv[1]`` (SAPIEN binds the denoiser when a camera is created), and prints one JSON line:
``{"mean", "std"}`` of the denoised frame (0..255) and ``"diff"``, its mean absolute difference to
the undenoised frame (0 = the denoiser did not run).
"""

import json
import sys

import numpy as np
import sapien


def probe(denoiser: str) -> None:

    sapien.render.set_camera_shader_dir("rt")
    sapien.render.set_ray_tracing_samples_per_pixel(2)
    sapien.render.set_ray_tracing_path_depth(2)
    scene = sapien.Scene()
    scene.set_ambient_light([0.3, 0.3, 0.3])
    scene.add_directional_light([0.3, 0.4, -1], [1, 1, 1])
    b = scene.create_actor_builder()
    b.add_box_visual(half_size=[0.1, 0.1, 0.1], material=sapien.render.RenderMaterial(base_color=[0.8, 0.3, 0.2, 1]))
    b.add_box_visual(pose=sapien.Pose([0, 0, -0.11]), half_size=[1, 1, 0.01], material=sapien.render.RenderMaterial(base_color=[0.6, 0.6, 0.6, 1]))
    b.build_static()
    frames = []
    for den in ("none", denoiser):  # the denoiser is bound when a camera is created
        sapien.render.set_ray_tracing_denoiser(den)
        cam = scene.add_camera(f"probe_{den}", 48, 32, 1.0, 0.01, 10.0)
        cam.entity.set_pose(sapien.Pose([-0.5, 0, 0.2], [0.9848, 0, 0.1736, 0]))
        scene.update_render()
        cam.take_picture()
        frames.append(np.clip(cam.get_picture("Color")[..., :3], 0, 1) * 255.0)
    print(json.dumps({"mean": float(frames[1].mean()), "std": float(frames[1].std()),
                      "diff": float(np.abs(frames[1] - frames[0]).mean())}), flush=True)


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] not in ("optix", "oidn", "none"):
        raise SystemExit("usage: render_probe.py {optix,oidn,none}")
    probe(sys.argv[1])
