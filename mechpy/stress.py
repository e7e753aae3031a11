"""mechpy.stress (being built)."""
