"""Build sources. Importing this package registers all of them in ``SOURCES``."""

from asset_pipeline.sources import folder, asset_packages, procedural_src, sim_packages  # noqa: F401  (registration; order = SOURCES order)
from asset_pipeline.sources.source import SOURCES, SourceDef, SourceItem, package_dir

DEFAULT_SOURCES = ("procedural", "ycb", "libero", "robosuite", "rgb_objects", "robocasa", "pybullet",
                   "metaworld", "gymnasium_robotics", "genesis", "maniskill")

__all__ = ["SOURCES", "SourceDef", "SourceItem", "DEFAULT_SOURCES", "package_dir"]
