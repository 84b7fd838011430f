"""What a policy answers, checked where it arrives: one action chunk per row in the env's DROID
action space, and a server's metadata.

``check_chunk`` turns one reply's actions into a (T, dim) float32 chunk or raises ``ReplyError``
naming the source and what is wrong: not numbers (strings, objects, booleans), not (T, dim) (a
scalar, (1, T, 8), (T, 7) for a joint space), empty (T = 0), NaN / Inf (checked in float64, so a
finite 1e39 is "outside the bounds", not "Inf"), or far outside the action space's bounds. "Far" is
more than a quarter of a dimension's range beyond it: a policy's small overshoot is normal (the env
clips it, with one warning), a chunk in other units or scale is a broken reply. ``check_output``
applies the same checks to a whole batch (in-process policies: LeRobot, any Python policy), so a bad
row fails its episode and the run goes on.

``ReplyError`` is a ``RuntimeError``: a policy or its server failed, not the user's input.
"""

from __future__ import annotations

import numpy as np

BOUNDS_MARGIN = 0.25  # share of a dimension's range a value may lie beyond the bound (then clipped)


class ReplyError(RuntimeError):
    """A policy's reply or metadata that cannot be used; the message names its source."""


def _space(env_kwargs: dict | None):
    from realm_ms.agents.droid_action_spaces import make_action_space

    kw = env_kwargs or {}
    return make_action_space(kw.get("action_space", "joint_position"), kw.get("gripper_action_space"))


def check_chunk(actions, space, source: str) -> np.ndarray:
    """One row's actions as a (T, dim) float32 chunk (a single (dim,) action is T = 1); ``space``:
    a ``DroidActionSpace``. Raises ``ReplyError`` saying what is wrong."""
    if isinstance(actions, (str, bytes, dict)) or actions is None:
        raise ReplyError(f"{source}: actions are a {type(actions).__name__}, not an array of numbers")
    try:
        a = np.asarray(actions)
    except (TypeError, ValueError) as e:  # ragged lists
        raise ReplyError(f"{source}: actions are not an array of numbers ({e})") from None
    if a.dtype.kind not in "iuf":
        raise ReplyError(f"{source}: actions have dtype {a.dtype}; expected numbers (int or float)")
    if a.ndim == 1 and a.shape[0] == space.dim:
        a = a[None]
    if a.ndim != 2 or a.shape[1] != space.dim:
        raise ReplyError(f"{source}: actions have shape {a.shape}; expected (T, {space.dim}) for the {space.action_space} action space "
                         f"(joint spaces: 8 = 7 joints + gripper; Cartesian: 7)")
    if a.shape[0] == 0:
        raise ReplyError(f"{source}: an empty action chunk (0 actions); expected at least 1")
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        t, d = np.argwhere(~np.isfinite(a))[0]
        raise ReplyError(f"{source}: actions contain NaN or Inf (action {t}, dim {d}: {a[t, d]})")
    lo, hi = (b.astype(np.float64) for b in space.bounds())
    pad = BOUNDS_MARGIN * (hi - lo)
    far = (a < lo - pad) | (a > hi + pad)
    if far.any():
        t, d = np.argwhere(far)[0]
        raise ReplyError(f"{source}: action {t}, dim {d} = {a[t, d]:.6g} is far outside the {space.action_space}:{space.gripper} "
                         f"bounds [{lo[d]:.4g}, {hi[d]:.4g}]")
    return a.astype(np.float32)


def check_output(out, n_rows: int, env_kwargs: dict | None, source: str):
    """A policy's ``PolicyOutput`` for ``n_rows`` rows, validated: returns (actions (B, T, dim) float32
    with bad rows left as they are, errors per row or None). An output that is not (B, T, dim) at all
    fails every row."""
    space = _space(env_kwargs)
    errors = list(out.errors) if getattr(out, "errors", None) else [None] * n_rows
    acts = getattr(out, "actions", None)
    try:
        a = np.asarray(acts)
        ok = a.dtype.kind in "iuf" and a.ndim == 3 and a.shape[0] == n_rows and a.shape[2] == space.dim
    except (TypeError, ValueError):
        ok = False
    if not ok:
        shape = getattr(acts, "shape", type(acts).__name__)
        why = f"{source}: returned actions of shape {shape}; expected ({n_rows}, T, {space.dim}) for {n_rows} row(s)"
        if not hasattr(out, "actions"):
            why = f"{source}: returned a {type(out).__name__}, not a PolicyOutput with actions ({n_rows}, T, {space.dim})"
        return np.zeros((n_rows, 1, space.dim), np.float32), [e or why for e in errors]
    for i in range(n_rows):
        if errors[i] is None:
            try:
                check_chunk(a[i], space, source)
            except ReplyError as e:
                errors[i] = str(e)
    return a.astype(np.float32, copy=False), (errors if any(errors) else None)


def check_metadata(meta, source: str) -> dict:
    """A server's metadata must be a map (msgpack dict) with text keys."""
    if not isinstance(meta, dict):
        raise ReplyError(f"{source}: its metadata is a {type(meta).__name__}, not a map of settings")
    bad = [k for k in meta if not isinstance(k, str)]
    if bad:
        raise ReplyError(f"{source}: its metadata has keys that are not text: {bad[:3]}")
    return meta


def metadata_action_space(meta: dict, source: str, space_key: str = "action_space", gripper_key: str | None = "gripper_action_space",
                          allowed: tuple[str, ...] | None = None) -> dict:
    """Env keywords of the action space a server's metadata declares (``{}``: joint_position); a bad
    declaration names the server and the field, never a flag."""
    from realm_ms.agents.droid_action_spaces import ACTION_SPACES, GRIPPER_SPACES, parse_action_space_flag

    space = meta.get(space_key)
    grip = meta.get(gripper_key) if gripper_key else None
    if space is None and grip is None:
        return {}
    known = allowed or ACTION_SPACES
    if not isinstance(space, str) or space not in known:
        raise ReplyError(f"{source}: its metadata declares {space_key} {space!r}; known: {', '.join(known)}")
    if grip is not None and (not isinstance(grip, str) or grip not in GRIPPER_SPACES):
        raise ReplyError(f"{source}: its metadata declares {gripper_key} {grip!r}; known: {', '.join(GRIPPER_SPACES)}")
    return parse_action_space_flag(f"{space}:{grip}" if grip else space)
