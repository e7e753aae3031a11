"""mechpy.variational (being built)."""
