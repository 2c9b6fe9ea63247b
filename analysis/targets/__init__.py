"""make targets, make million: the speed targets per scene."""
