"""Rendering: every shader x camera renders a non-blank frame, ray-traced exposure matches raster,
the denoiser is decided once (and never silently), V-LIGHT maps onto our light units.
Runs on lavapipe (CPU) in CI and on a GPU: frames are checked by statistics, not pixels.

Each ray-traced shader renders in a child process, so that one render's crash names its shader
instead of killing the test session; the raster shader renders in the test process. Ray-traced frames on lavapipe are rendered one camera at a time
(``RealmEnv.capture_sensor_data``): with all three in flight at once, the child crashed in about
one run in two and the frames that survived differed from run to run.
"""

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import realm_ms  # noqa: F401
from realm_ms import rendering
from realm_ms.rendering import frame_stats

ENV = "REALM-PickApple-v1"
SIZE = dict(camera_width=64, camera_height=36)
SHADERS = ("default", "rt-fast", "rt")
CAMERAS = ("exterior_1", "exterior_2", "wrist")
# rt exposure vs raster on the same scene: mean within MEAN_TOL (0..255), contrast ratio within CONTRAST_TOL
MEAN_TOL = 15.0
CONTRAST_TOL = (0.75, 1.33)


def render(env_id: str, shader: str, size: dict) -> tuple[dict, dict]:
    """(camera -> HxWx3 uint8, camera -> ray-tracing denoiser) of ``env_id`` after reset (seed 0)."""
    import gymnasium as gym

    with warnings.catch_warnings(), rendering.rt_samples_per_pixel(4):
        warnings.simplefilter("ignore")
        env = gym.make(env_id, obs_mode="rgb", shader=shader, **size)
        try:
            obs, _ = env.reset(seed=0)
            frames = {cam: obs["sensor_data"][cam]["rgb"][0].cpu().numpy() for cam in obs["sensor_data"]}
            denoisers = {k: c.shader_config.shader_pack_config.get("ray_tracing_denoiser")
                         for k, c in env.unwrapped._sensor_configs.items()}
        finally:
            env.close()
    return frames, denoisers


_CHILD = """
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[5])
from test_rendering import render

frames, denoisers = render(sys.argv[1], sys.argv[2], json.loads(sys.argv[4]))
np.savez(sys.argv[3], **frames)
with open(sys.argv[3] + ".json", "w") as f:
    json.dump(denoisers, f)
"""


def _render_in_child(shader: str, out: Path) -> tuple[dict, dict]:
    """:func:`render` in a child process."""
    cmd = [sys.executable, "-c", _CHILD, ENV, shader, str(out), json.dumps(SIZE), str(Path(__file__).parent)]
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    if res.returncode != 0:
        pytest.fail(f"{shader} render exited {res.returncode}:\n{res.stdout[-2000:]}\n{res.stderr[-4000:]}")
    with np.load(str(out) + ".npz") as z:
        frames = {k: z[k] for k in z.files}
    return frames, json.loads(Path(str(out) + ".json").read_text())


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    """{shader: {camera: HxWx3 uint8}} of one task after reset (seed 0), each ray-traced shader in a
    child process (see the module docstring), the raster one in this process. ``rt`` keeps its path
    depth but renders 4 spp instead of 32 so the module stays within CI time on lavapipe."""
    out = {}
    tmp = tmp_path_factory.mktemp("frames")
    for shader in SHADERS:
        render_here = shader == "default"
        out[shader], out[shader + "/denoisers"] = (render(ENV, shader, SIZE) if render_here else
                                                   _render_in_child(shader, tmp / shader))
    out["rt-fast/again"], _ = _render_in_child("rt-fast", tmp / "rt-fast-again")
    return out


@pytest.mark.render
@pytest.mark.parametrize("shader", SHADERS)
def test_every_camera_renders_non_blank(frames, shader):
    assert set(CAMERAS) <= set(frames[shader])
    for cam in CAMERAS:
        img = frames[shader][cam]
        assert img.shape == (36, 64, 3)
        mean, std = frame_stats(img)
        assert std > 8.0, f"{shader}/{cam}: blank frame (std {std:.1f})"
        assert 25.0 < mean < 235.0, f"{shader}/{cam}: black or blown-out frame (mean {mean:.1f})"


@pytest.mark.render
@pytest.mark.skipif(rendering.cuda_available(), reason="a GPU denoiser need not be bit-exact; the race was lavapipe's")
def test_ray_traced_frames_are_reproducible(frames):
    """The same scene, seed and sample count ray-traced in two processes gives the same pixels
    (frames in flight together on lavapipe corrupted the first camera's)."""
    for cam in CAMERAS:
        a, b = frames["rt-fast"][cam].astype(int), frames["rt-fast/again"][cam].astype(int)
        assert np.array_equal(a, b), f"rt-fast/{cam}: {np.mean(a != b):.1%} of values differ, up to {np.abs(a - b).max()}"


@pytest.mark.render
@pytest.mark.parametrize("shader", ("rt-fast", "rt"))
def test_rt_exposure_matches_raster(frames, shader):
    for cam in CAMERAS:
        m0, s0 = frame_stats(frames["default"][cam])
        m1, s1 = frame_stats(frames[shader][cam])
        assert abs(m1 - m0) < MEAN_TOL, f"{shader}/{cam}: mean {m1:.1f} vs raster {m0:.1f}"
        assert CONTRAST_TOL[0] < s1 / s0 < CONTRAST_TOL[1], f"{shader}/{cam}: contrast {s1:.1f} vs raster {s0:.1f}"


@pytest.mark.render
@pytest.mark.parametrize("shader", ("rt-fast", "rt"))
def test_one_denoiser_for_every_camera(frames, shader):
    denoisers = frames[shader + "/denoisers"]
    assert set(CAMERAS) <= set(denoisers)
    chosen = {denoisers[cam] for cam in CAMERAS}
    assert chosen == {rendering.resolve_denoiser("auto")}


@pytest.mark.render
def test_the_next_env_keeps_the_renderer_and_renders_the_same_frames(frames):
    """An env made after another was closed reuses the process's renderer (``keep_renderer``: a new
    one recomputes its BRDF table on its first picture, seconds on lavapipe) and renders the same
    frames as the first env did."""
    again, _ = render(ENV, "default", SIZE)
    assert len(rendering._KEPT) == 1
    for cam in CAMERAS:
        assert np.array_equal(again[cam], frames["default"][cam]), cam


def test_denoiser_is_probed_and_never_silent():
    rendering.resolve_denoiser.cache_clear()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        a = rendering.camera_shader_config("rt-fast")
        b = rendering.camera_shader_config("rt", "auto")
    msgs = [str(x.message) for x in w if "denoiser" in str(x.message)]
    assert len(msgs) == 1 and a.shader_pack_config["ray_tracing_denoiser"] in msgs[0]
    assert a.shader_pack_config["ray_tracing_denoiser"] == b.shader_pack_config["ray_tracing_denoiser"]
    if not rendering.cuda_available():
        assert a.shader_pack_config["ray_tracing_denoiser"] == "none"
        # forcing a denoiser that cannot run here is an error, not a black or noisy frame
        res = rendering.probe_denoiser("oidn")
        assert not res.ok and res.reason
        with pytest.raises(rendering.DenoiserUnavailable, match="oidn"):
            rendering.resolve_denoiser("oidn")
    else:  # a GPU: auto picks a denoiser that passed its probe, or none with the reasons named
        chosen = a.shader_pack_config["ray_tracing_denoiser"]
        assert chosen == "none" or rendering.probe_denoiser(chosen).ok
    assert rendering.camera_shader_config("rt", "none").shader_pack_config["ray_tracing_denoiser"] == "none"
    assert "ray_tracing_denoiser" not in rendering.camera_shader_config("default", "none").shader_pack_config


def test_bad_names_are_clear_errors():
    with pytest.raises(ValueError, match="unknown shader"):
        rendering.camera_shader_config("raytrace")
    with pytest.raises(ValueError, match="unknown denoiser"):
        rendering.camera_shader_config("rt", "nvidia")


def test_rt_samples_cap():
    with rendering.rt_samples_per_pixel(4):
        fast = rendering.camera_shader_config("rt-fast", "none").shader_pack_config
        full = rendering.camera_shader_config("rt", "none").shader_pack_config
    assert fast["ray_tracing_samples_per_pixel"] == 2 and full["ray_tracing_samples_per_pixel"] == 4
    assert full["ray_tracing_path_depth"] == 16  # only the samples are capped
    assert rendering.camera_shader_config("rt", "none").shader_pack_config["ray_tracing_samples_per_pixel"] == 32
    with pytest.raises(ValueError):
        with rendering.rt_samples_per_pixel(0):
            pass
