"""mechpy.inertia (being built)."""
