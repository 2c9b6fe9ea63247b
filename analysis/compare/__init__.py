"""make compare: two psweep results folders configuration by configuration."""
