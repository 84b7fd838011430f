"""Robot model files (``MODEL.yaml``): which effects, their parameters, and provenance.

Format (documented in ``docs/sysid.md``)::

    realm_ms_robot_model: 1
    gains: polymetis            # DROID gain preset the model was identified with
    joint_physics: none         # PhysX joint friction/armature preset underneath the effects
    physics_hz: 120
    effects:
      - name: coulomb_friction
        config: {asymmetric: false}
        params: {fc1: 0.12, ..., fc7: 0.31, fc_asym1: 0.0, ...}
        units: {fc: N·m, fc_asym: N·m}
    provenance: {data: ..., created: ..., realm_ms: ..., sapien: ...}

``load_actuation_model(path_or_dict)`` returns the :class:`ActuationModel` the benchmark controller
installs with ``set_robot_model`` (light imports: torch + yaml). The sysid workbench writes these
files; the benchmark reads them, so the format lives here, below both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from realm_ms.agents.actuation import ActuationModel
from realm_ms.agents.effects import Effect, effect_class, make_effect
from realm_ms.atomic import write_text
from realm_ms.errors import InputError

FORMAT_VERSION = 1
#: robot models shipped with the package, by name: ``robot_model="droid-aligned"`` anywhere a robot
#: model is accepted (``gym.make``, ``realm eval --robot-model``, ``realm export``, the LeRobot env type)
NAMED_MODELS = {"droid-aligned": "droid_aligned.yaml"}


def named_model_path(name: str) -> Path:
    """The package file of a named robot model (``NAMED_MODELS``)."""
    return Path(__file__).resolve().parent / "assets" / NAMED_MODELS[name]


#: the benchmark's policy rate; physics must run a whole number of steps per control step
CONTROL_HZ = 15
#: physics rates accepted: 60 Hz (4 steps per control step) to 2 kHz (133); the envs default to
#: 120 Hz, and a rate such as 1.5 MHz, a multiple of 15, would take hours per control step (a hang)
PHYSICS_HZ_RANGE = (60.0, 2000.0)


def check_physics_hz(value: Any, where: str = "physics_hz") -> float:
    """A physics rate in Hz: a multiple of the 15 Hz control rate (e.g. 120) within ``PHYSICS_HZ_RANGE``."""
    try:
        hz = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: expected a number in Hz, got {value!r}") from None
    if not math.isfinite(hz) or hz <= 0:
        raise InputError(f"{where}: must be a positive number of Hz, got {value!r}")
    lo, hi = PHYSICS_HZ_RANGE
    if not lo <= hz <= hi:
        raise InputError(f"{where}: {hz:g} Hz is outside the supported {lo:g}-{hi:g} Hz (e.g. 120, 240, 480)")
    steps = hz / CONTROL_HZ
    if abs(steps - round(steps)) > 1e-9 or round(steps) < 1:
        raise InputError(f"{where}: {hz:g} Hz is not a whole multiple of the {CONTROL_HZ} Hz control rate "
                         f"(e.g. 120, 240, 480)")
    return hz


# settings that divide (tanh widths): 0 is a division by zero, a negative width flips the switch
POSITIVE_SETTINGS = {"direction_velocity": "rad/s", "torque_width": "N·m"}


def check_settings(effect: Effect, where: str) -> None:
    """An effect's settings (``config``) have the type of their defaults: true/false, finite
    numbers, tuples of as many finite numbers; widths (``POSITIVE_SETTINGS``) are > 0."""
    import dataclasses

    for f in dataclasses.fields(effect.config):
        v = getattr(effect.config, f.name)
        default = f.default if f.default is not dataclasses.MISSING else f.default_factory()  # type: ignore[misc]
        unit = POSITIVE_SETTINGS.get(f.name)
        if isinstance(default, bool):
            if not isinstance(v, bool):
                raise InputError(f"{where}.{f.name}: expected true or false, got {v!r}")
            continue
        values = v if isinstance(default, tuple) else (v,)
        if isinstance(default, tuple) and (not isinstance(v, tuple) or len(v) != len(default)):
            raise InputError(f"{where}.{f.name}: expected a list of {len(default)} numbers, got {v!r}")
        for x in values:
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                raise InputError(f"{where}.{f.name}: expected {'finite numbers' if values is v else 'a finite number'}, got {v!r}")
            if unit and x <= 0:
                raise InputError(f"{where}.{f.name}: must be > 0 {unit} (a tanh width), got {v!r}")


def check_effects(effects: list[Effect], where: str, labels: list[str] | None = None) -> None:
    """The one validation of an effect list, for the loader, ``RobotModel`` and ``--add``/``--hidden``:
    each effect's settings (``check_settings``) and no effect twice (both would be applied)."""
    seen: dict[str, str] = {}
    for i, e in enumerate(effects):
        label = labels[i] if labels else e.name
        check_settings(e, f"{where}{label}.config")
        if e.name in seen:
            if seen[e.name] == label:  # named by the effect alone (a spec on the command line)
                raise InputError(f"{where}effect {e.name!r} given twice; give it once")
            raise InputError(f"{where}{label}: effect {e.name!r} given twice (also {seen[e.name]}); give it once")
        seen[e.name] = label


# other spellings of the units the effects use, as (unit, factor to it); anything else is refused
_UNIT_SPELLINGS = {"N·m": {"Nm": 1.0, "N m": 1.0, "N*m": 1.0, "N.m": 1.0, "mN·m": 1e-3, "mNm": 1e-3, "mN m": 1e-3,
                           "mN*m": 1e-3, "kN·m": 1e3},
                   "rad": {"mrad": 1e-3, "deg": math.pi / 180, "°": math.pi / 180},
                   "rad/s": {"mrad/s": 1e-3, "deg/s": math.pi / 180},
                   "kg": {"g": 1e-3}, "s": {"ms": 1e-3}, "m": {"mm": 1e-3, "cm": 1e-2},
                   "kg·m²": {"kg m^2": 1.0, "kg*m^2": 1.0, "kg·m^2": 1.0, "kgm^2": 1.0}}


def unit_factor(given: Any, unit: str, where: str) -> float:
    """The factor that turns a value in ``given`` into ``unit`` (1 for the same unit); ValueError for
    a unit that is not a known spelling or scale of ``unit``."""
    text = str(given).strip()
    if text == unit:
        return 1.0
    factor = _UNIT_SPELLINGS.get(unit, {}).get(text)
    if factor is None:
        raise InputError(f"{where}: {text!r} is not {unit} and cannot be converted to it; write the values in {unit}")
    return factor


def _convert_units(name: str, params: dict, config: dict, units: Any, where: str) -> dict:
    """``params`` in the units the effect declares: ``units: {fc: mN·m}`` scales every fc value."""
    if units is None:
        return params
    if not isinstance(units, dict):
        raise InputError(f"{where}: expected a mapping of parameter -> unit, got {units!r}")
    effect = make_effect(name, None, config)
    specs = {s.name: s for s in effect.specs}
    spec_of = {p.local_key: p.spec.name for p in effect.params} | {n: n for n in specs}  # fc4 -> fc
    factors = {}
    for key, given in units.items():
        if key not in specs:
            raise InputError(f"{where}.{key}: effect {name!r} has no parameter {key!r}; it has {', '.join(specs)}")
        factors[key] = unit_factor(given, specs[key].unit, f"{where}.{key}")
    out = {}
    for key, v in params.items():
        f = factors.get(spec_of.get(key), 1.0)
        if f != 1.0 and not isinstance(v, bool):
            try:
                v = (np.asarray(v, dtype=float) * f).tolist()
            except (TypeError, ValueError):
                pass  # not numeric: set_values names it
        out[key] = v
    return out


@dataclass
class RobotModel:
    effects: list[Effect] = field(default_factory=list)
    gains: str = "polymetis"
    joint_physics: str = "none"
    physics_hz: float = 120.0
    provenance: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.physics_hz = check_physics_hz(self.physics_hz)
        check_effects(self.effects, "effects: ")

    def actuation(self) -> ActuationModel:
        """The arm's stages in canonical order (measure/command first, friction last)."""
        return ActuationModel(sorted(self.arm_effects, key=lambda e: e.order))

    @property
    def arm_effects(self) -> list[Effect]:
        """The effects on the arm: what the arm's controller and the arm replay run."""
        return [e for e in self.effects if e.acts_on == "arm"]

    @property
    def gripper_effects(self) -> list[Effect]:
        """The effects on the gripper: what the gripper controller runs and the gripper row judges."""
        return [e for e in self.effects if e.acts_on != "arm"]

    def gripper_law(self):
        """The gripper controller's law (``gripper_response``), or None: the nominal gripper."""
        fx = self.effect("gripper_response")
        return fx.law() if fx is not None else None

    @property
    def names(self) -> list[str]:
        return [e.name for e in self.effects]

    def effect(self, name: str) -> Effect | None:
        return next((e for e in self.effects if e.name == name), None)

    def params(self) -> dict[str, float]:
        return {f"{e.name}.{k}": v for e in self.effects for k, v in e.values().items()}

    def params_at_bounds(self) -> dict[str, str]:
        """Fitted parameters pressed against a bound, ``{"link_mass.s2": "lower"}``."""
        out = {}
        for e in self.effects:
            values = e.values()
            for p in e.free_params:
                side = p.spec.at_bound(values[p.local_key])
                if side:
                    out[p.key] = side
        return out

    def to_dict(self) -> dict[str, Any]:
        from dataclasses import asdict

        return {
            "realm_ms_robot_model": FORMAT_VERSION,
            "gains": self.gains,
            "joint_physics": self.joint_physics,
            "physics_hz": float(self.physics_hz),
            "effects": [
                {
                    "name": e.name,
                    "config": {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(e.config).items()},
                    "params": {k: round(v, 9) for k, v in e.values().items()},
                    "units": {s.name: s.unit for s in e.specs},
                }
                for e in self.effects
            ],
            "provenance": dict(self.provenance),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any], where: str = "robot model") -> "RobotModel":
        """Parse and validate; every problem is a one-line ``ValueError`` naming ``where`` and the field."""
        if not isinstance(data, dict):
            raise InputError(f"{where}: expected a mapping at the top level, got {type(data).__name__}")
        _check_keys(data, ("realm_ms_robot_model", "gains", "joint_physics", "physics_hz", "effects", "provenance"), where)
        version = data.get("realm_ms_robot_model", FORMAT_VERSION)
        if version != FORMAT_VERSION:
            raise InputError(f"{where}: format version {version} not supported (expected {FORMAT_VERSION})")
        items = data.get("effects") or []
        if not isinstance(items, list):
            raise InputError(f"{where}: effects: expected a list of effects (e.g. `effects: [{items}]`), "
                             f"got {type(items).__name__} {items!r}")
        effects = []
        for i, item in enumerate(items):
            if isinstance(item, str):
                item = {"name": item}
            if not isinstance(item, dict) or "name" not in item:
                raise InputError(f"{where}: effects[{i}]: expected a name or a mapping with 'name', got {item!r}")
            _check_keys(item, ("name", "params", "config", "units"), f"{where}: effects[{i}]", "an effect")
            for key in ("params", "config"):
                if item.get(key) is not None and not isinstance(item[key], dict):
                    raise InputError(f"{where}: effects[{i}].{key}: expected a mapping, got {item[key]!r}")
            try:
                effect_class(item["name"])
                config = item.get("config") or {}
                params = _convert_units(item["name"], item.get("params") or {}, config, item.get("units"),
                                        "units")
                effects.append(make_effect(item["name"], params, config))
            except (KeyError, ValueError, TypeError) as e:
                msg = e.args[0] if isinstance(e, KeyError) and e.args else e
                raise InputError(f"{where}: effects[{i}]: {msg}") from None
        check_effects(effects, f"{where}: ", [f"effects[{i}]" for i in range(len(effects))])
        from realm_ms.agents.control.presets import GAIN_PRESETS, JOINT_PHYSICS_PRESETS

        presets = {}
        for key, table, default in (("gains", GAIN_PRESETS, "polymetis"), ("joint_physics", JOINT_PHYSICS_PRESETS, "none")):
            presets[key] = str(data.get(key, default))
            if presets[key] not in table:
                raise InputError(f"{where}: {key}: unknown preset {presets[key]!r}; choose one of {', '.join(sorted(table))}")
        return cls(
            effects,
            gains=presets["gains"],
            joint_physics=presets["joint_physics"],
            physics_hz=check_physics_hz(data.get("physics_hz", 120.0), f"{where}: physics_hz"),
            provenance=dict(data.get("provenance") or {}),
        )

    def save(self, path: str | Path) -> None:
        import yaml

        path = Path(path)
        RobotModel.from_dict(self.to_dict(), str(path))  # never write a file the loader would refuse
        write_text(path, yaml.safe_dump(self.to_dict(), sort_keys=False, allow_unicode=True))

    @classmethod
    def load(cls, path_or_dict: str | Path | dict | "RobotModel" | None) -> "RobotModel":
        if path_or_dict is None:
            return cls()
        if isinstance(path_or_dict, RobotModel):
            return path_or_dict
        if isinstance(path_or_dict, dict):
            return cls.from_dict(path_or_dict)
        import yaml

        if isinstance(path_or_dict, str) and path_or_dict in NAMED_MODELS:
            path_or_dict = named_model_path(path_or_dict)
        path = Path(path_or_dict)
        if not path.is_file():
            raise FileNotFoundError(f"robot model {path} not found" + (" (it is a directory)" if path.is_dir() else "")
                                    + f"; give a MODEL.yaml path or a named model ({', '.join(NAMED_MODELS)})")
        try:
            data = yaml.safe_load(path.read_text())
        except UnicodeDecodeError:
            raise InputError(f"{path}: not a text (YAML) file") from None
        except yaml.YAMLError as e:
            first = str(e).strip().splitlines()[0] if str(e).strip() else "syntax error"
            raise InputError(f"{path}: not valid YAML ({first})") from None
        return cls.from_dict(data, str(path))

    def copy(self) -> "RobotModel":
        return RobotModel.from_dict(self.to_dict())


def _check_keys(data: dict, known: tuple[str, ...], where: str, what: str = "a robot model") -> None:
    """A key the loader does not read is an error, not ignored: a misspelt ``effect:`` would
    otherwise load the nominal robot without a word."""
    import difflib

    unknown = [k for k in data if k not in known]
    if unknown:
        near = difflib.get_close_matches(str(unknown[0]), known, n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise InputError(f"{where}: unknown key {unknown[0]!r}{hint}; {what} has {', '.join(known)}")


def load_robot_model(path_or_dict) -> RobotModel:
    return RobotModel.load(path_or_dict)


def load_actuation_model(path_or_dict) -> ActuationModel:
    """The arm's stages: ``controller.set_robot_model(load_actuation_model("MODEL.yaml"))``
    then ``actuation.build(articulation, joint_indices)`` once the articulation is loaded (armature,
    payload). Use the file's ``gains`` and ``joint_physics`` presets for the controller too
    (``load_robot_model(path).gains`` / ``.joint_physics``)."""
    return RobotModel.load(path_or_dict).actuation()
