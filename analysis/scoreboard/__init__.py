"""The scoreboard: external programs beside psim's engines, judged and timed (make scoreboard)."""
