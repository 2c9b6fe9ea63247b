"""make regress, make regress-baseline: the regression suite against its baseline."""
