"""The policy's latency on the simulated robot's clock (``realm eval --policy-latency``).

On hardware the world keeps moving while a policy thinks: the arm keeps tracking its last target for
the 100-500 ms a VLA takes, and the next chunk starts from where the arm has got to. ``realm eval``
models it by holding each slot's previous joint target for the latency before its new chunk starts
(``tasks.episode.EpisodeEngine.run``'s delays), so the observation the policy saw is as stale as on
the robot. The setting:

- ``0`` (default): time stops during inference (REALM's protocol, comparable with its numbers);
- ``SECONDS``: a fixed latency for every request;
- ``measured``: each request's own wall time (server policies: the request's round trip; in-process
  policies: the ``act`` call of the round).

Rounding rule: the hold lasts whole control steps (15 Hz), the latency rounded to the nearest step,
halves up: ``steps = floor(latency * 15 + 0.5)``. A fixed 0.3 s is 4.5 steps and holds 5; a measured
0.3 s plus up to 66 ms of overhead (< 5.5 steps) holds the same 5, so the two give the same records.
"""

from __future__ import annotations

import math

import numpy as np

CONTROL_HZ = 15
MEASURED = "measured"


def parse_latency(value) -> str:
    """``0`` | ``measured`` | a finite number of seconds >= 0, normalised to text (records and the
    fingerprint store it); ``ValueError`` saying what is accepted."""
    from realm_ms.validate import InputError, check_number

    if isinstance(value, str) and value.strip().lower() == MEASURED:
        return MEASURED
    try:
        s = check_number(value, "--policy-latency", "s", minimum=0.0)
    except ValueError as e:
        raise InputError(f"{e}; or 'measured' (each request's wall time)") from None
    if s == 0:
        return "0"  # also -0
    if s > 60:
        raise InputError(f"--policy-latency: {s:g} s is more than 60 s; give seconds (e.g. 0.3), 0, or 'measured'")
    return f"{s:g}"


def hold_steps(setting: str, measured_s: float) -> int:
    """Control steps to hold the previous target for one request (the module's rounding rule)."""
    s = measured_s if setting == MEASURED else float(setting)
    return int(math.floor(max(s, 0.0) * CONTROL_HZ + 0.5))


def latency_summary(records: list[dict]) -> dict:
    """Per server: requests, median and p95 of the measured latencies (s), from records' ``latency_s``
    ({server: [s, ...]}); and the settings used (``policy_latency``)."""
    per: dict[str, list[float]] = {}
    settings = sorted({str(r.get("policy_latency", "0")) for r in records if r.get("status") in ("ok", "error")})
    for r in records:
        for server, vals in (r.get("latency_s") or {}).items():
            if isinstance(vals, list):
                per.setdefault(str(server), []).extend(float(v) for v in vals if isinstance(v, (int, float)))
    servers = {k: dict(requests=len(v), median_s=round(float(np.median(v)), 4), p95_s=round(float(np.percentile(v, 95)), 4))
               for k, v in sorted(per.items()) if v}
    return dict(settings=settings, servers=servers)
