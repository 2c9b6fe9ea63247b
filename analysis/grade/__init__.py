"""make grade: every submission of a folder judged and timed through psweep, a scoreboard and a
report per submission."""
