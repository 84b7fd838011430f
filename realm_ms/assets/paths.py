"""Where catalogs and cached procedural meshes live (both overridable by environment variables)."""

from __future__ import annotations

import os
from pathlib import Path

ENV_CATALOG = "REALM_ASSETS_DIR"  # the catalog the envs use (``realm assets build --out`` target)
ENV_CACHE = "REALM_ASSETS_CACHE"  # on-the-fly procedural meshes


def _xdg_cache() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "realm_ms"


def default_catalog_dir() -> Path:
    return Path(os.environ.get(ENV_CATALOG) or _xdg_cache() / "catalog").expanduser()


def cache_dir() -> Path:
    return Path(os.environ.get(ENV_CACHE) or _xdg_cache() / "procedural").expanduser()
