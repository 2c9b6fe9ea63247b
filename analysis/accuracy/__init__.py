"""make accuracy: error against run time of the discrete engines."""
