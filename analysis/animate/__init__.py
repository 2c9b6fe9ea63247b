"""make animate: a scene as a GIF."""
