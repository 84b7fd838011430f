"""4 V-LIGHT: one intensity for every scene light and a warm colour per light, drawn per reset.

REALM: I ~ U(20,000, 750,000) (Omniverse light intensity, nits-like) on every light whose prim
name contains "light"; colour per light ~ N([255, 214, 170], 15) per channel, clipped, / 255.
Our lights (SAPIEN point and directional lights) are linear RGB radiance; a light's colour is
``nominal_gain * (I / I_REF) * c``, where ``nominal_gain`` is the largest channel of the scene's own
colour for that light and ``I_REF`` = 122,474 (the geometric mean of REALM's range), so the range
maps onto x0.16 .. x6.1 of each scene's nominal brightness. Ambient light (the analogue of the
BEHAVIOR sky/dome) is left as is, as REALM leaves non-"light" prims. Applied at episode init from
the nominal colours recorded at load: nothing compounds.
"""

from __future__ import annotations

import numpy as np

from realm_ms.tasks.perturbation import Perturbation, as_float

INTENSITY = (20_000.0, 750_000.0)
I_REF = float(np.sqrt(INTENSITY[0] * INTENSITY[1]))  # 122,474
COLOUR_MEAN = (255.0, 214.0, 170.0)
COLOUR_STD = 15.0
MAX_LIGHTS = 8  # colours drawn per reset (scenes have 2-4 lights)


def light_colour(nominal, intensity: float, colour) -> tuple[float, float, float]:
    gain = max(nominal) * intensity / I_REF
    return tuple(float(gain * c) for c in colour)


class VLight(Perturbation):
    pid = 4
    name = "V-LIGHT"
    acts_on = "intensity and colour of every scene light (point + directional)"
    ranges = f"I ~ U{INTENSITY} -> x I/{I_REF:.0f} of the nominal; colour ~ N({list(COLOUR_MEAN)}, {COLOUR_STD}) / 255 per light"

    def draw(self, rng, ctx):
        c = np.clip(rng.normal(COLOUR_MEAN, COLOUR_STD, size=(MAX_LIGHTS, 3)), 0, 255) / 255.0
        return dict(intensity=as_float(rng.uniform(*INTENSITY)), colours=[[as_float(v) for v in row] for row in c])

    def on_episode_init(self, env, env_idx, params):
        lights = getattr(env, "lights", None)
        if not lights:
            return  # no render system (state-only): nothing to light
        for i, p in zip([int(i) for i in env_idx], params):
            scene_lights = lights[i] if len(lights) > i else lights[0]
            for k, (comp, nominal) in enumerate(scene_lights):
                comp.color = list(light_colour(nominal, p["intensity"], p["colours"][k % MAX_LIGHTS]))
