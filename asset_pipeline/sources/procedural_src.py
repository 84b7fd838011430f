"""The procedural generators as a build source: ``variants`` seeded objects per category."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from asset_pipeline.sources.source import SourceItem, register_source

DEFAULT_VARIANTS = 40


def _here() -> Path:
    return Path(__file__).resolve().parents[1] / "procedural"


@register_source("procedural", licence="MIT (realm-ms)", package=None, description="realm-ms procedural generators (exact semantics)",
                 locate=_here)
def procedural_items(root: Path, variants: int = DEFAULT_VARIANTS) -> Iterator[SourceItem]:
    from asset_pipeline.procedural import REGISTRY
    from asset_pipeline.procedural.materialize import generator_version

    ver = generator_version()
    for name in sorted(REGISTRY):
        for seed in range(variants):
            yield SourceItem(id=f"proc/{name}/{seed}", source="procedural", licence="MIT (realm-ms)", category=name,
                             procedural=(name, seed), real_mesh=False, name=f"{name} #{seed}", known_scale=True,
                             extra_files=[], mesh=None, collision_file=None, mesh_scale=1.0, up=ver)
