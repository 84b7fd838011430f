"""Processing stages, one module per concept: load -> repair -> normalise -> physics -> decompose ->
stable poses -> appearance (colours, thumbnail). ``asset_pipeline.process`` chains them."""


class MeshError(Exception):
    """A mesh that cannot be used (unreadable, empty, non-finite): the object is skipped and reported."""
