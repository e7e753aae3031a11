"""mechpy.modes (being built)."""
