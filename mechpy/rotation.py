"""mechpy.rotation (being built)."""
