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

    def __post_init__(self) -> None:
        # 0 or a negative timeout used to mean "unlimited" by accident: reject it
        if not (self.object_timeout_s > 0 and self.object_timeout_s < float("inf")):
            raise ValueError(f"object_timeout_s must be a positive number of seconds, got {self.object_timeout_s!r}")
        if int(self.workers) < 1:
            raise ValueError(f"workers must be >= 1, got {self.workers!r}")
        if int(self.procedural_variants) < 1:
            raise ValueError(f"procedural_variants must be >= 1, got {self.procedural_variants!r}")

    def output_key(self) -> str:
        d = asdict(self)
        for k in ("workers", "object_timeout_s", "procedural_variants"):
            d.pop(k)
        d["coacd"].pop("budget_s")
        return hashlib.sha1(repr(sorted(d.items())).encode()).hexdigest()[:10]
