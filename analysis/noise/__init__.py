"""make noise: quiet against one busy neighbour."""
