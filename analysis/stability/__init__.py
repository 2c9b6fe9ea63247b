"""make stability: stiff and extreme scenes through every engine."""
