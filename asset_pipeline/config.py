"""Build configuration (everything that changes outputs is part of the cache key)."""

from __future__ import annotations

import hashlib
from dataclasses import asdict, dataclass, field

from asset_pipeline.stages.decompose import CoacdSettings


@dataclass
class BuildConfig:
    coacd: CoacdSettings = field(default_factory=CoacdSettings)
    use_coacd: bool = True
    thumbnails: bool = True
    stable_poses: bool = True
    object_timeout_s: float = 240.0  # whole-object wall clock (CoACD has its own, shorter budget)
    workers: int = 1
    procedural_variants: int = 40

    def output_key(self) -> str:
        d = asdict(self)
        for k in ("workers", "object_timeout_s", "procedural_variants"):
            d.pop(k)
        d["coacd"].pop("budget_s")
        return hashlib.sha1(repr(sorted(d.items())).encode()).hexdigest()[:10]
