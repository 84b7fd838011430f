"""Object ids for the nouns REALM's tasks name, with sizes from the original configs / real objects.

``real/<name>`` ids are real meshes shipped as package data (``realm_ms.assets.real_objects``; the
procedural counterpart, which sets their size, mass and friction, is the fallback); the rest are
procedural (the cubes too: no registry package ships a scanned cube, docs/assets.md)."""

from __future__ import annotations

from realm_ms.assets.catalog import get_object_spec
from realm_ms.assets.object_spec import ObjectSpec

# noun -> object id; sizes (largest extent, m) follow the REALM task configs / real objects.
TASK_OBJECTS: dict[str, str] = {
    "green cube": "proc/cube/0?color=green&size=0.03",
    "yellow cube": "proc/cube/0?color=yellow&size=0.03",
    "blue cube": "proc/cube/0?color=blue&size=0.03",
    "orange cube": "proc/cube/0?color=orange&size=0.03",
    "red cube": "proc/cube/0?color=red&size=0.03",
    "bowl": "real/bowl",
    "tray": "proc/tray/0?color=brown&size=0.35",
    "box": "real/box",
    "banana": "real/banana",
    "orange": "proc/orange/0",
    "lemon": "proc/lemon/0",
    "dice": "proc/dice/0?color=white",
    "marker": "real/marker",
    "mug": "real/mug",
    "chocolate bar": "proc/chocolate_bar/0",
    "tea bag": "proc/tea_bag/0",
    "bag of cookies": "proc/bag_of_cookies/0",
    "spoon": "real/spoon",
    "teaspoon": "real/spoon",
    "can of soda": "proc/can_of_soda/0?color=red",
    "half apple": "proc/half_apple/0?color=red",
    "beaker": "proc/beaker/0",
    "water bottle": "real/water_bottle",
    "lid": "proc/lid/0",
    "plate": "proc/plate/0?color=white",
    "frying pan": "proc/frying_pan/0?color=black",
    "apple": "real/apple",
    "corkscrew": "proc/corkscrew/0",
    "knife": "proc/knife/0",
    "fork": "proc/fork/0",
    "wineglass": "proc/wineglass/0",
    "wine glass": "proc/wineglass/0",
    "water glass": "proc/water_glass/0",
    "wine bottle": "proc/wine_bottle/0",
    "jar": "proc/jar/0",
    "ticket": "proc/ticket/0",
}


def task_object_spec(noun: str) -> ObjectSpec:
    try:
        oid = TASK_OBJECTS[noun]
    except KeyError:
        raise KeyError(f"no task object {noun!r}; known: {sorted(TASK_OBJECTS)}") from None
    return get_object_spec(oid)
