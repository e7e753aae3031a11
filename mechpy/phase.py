"""Phase space and chaos (placeholder, filled below)."""
