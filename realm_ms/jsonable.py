"""``jsonable``: nested records (dicts, lists, tensors, arrays, numpy scalars) as plain JSON values."""

from __future__ import annotations

import math

import numpy as np


def jsonable(x):
    """Tensors / arrays / numpy scalars inside nested dicts and lists -> plain JSON values: keys as
    strings, a one-element vector as its value, non-finite floats as None (JSON has no inf/nan)."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if hasattr(x, "detach"):
        x = x.detach().cpu().numpy()
    if isinstance(x, np.ndarray):
        x = x.tolist()
        return x[0] if isinstance(x, list) and len(x) == 1 and not isinstance(x[0], list) else x
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
