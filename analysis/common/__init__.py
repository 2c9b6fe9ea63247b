"""What several tools share: loading results, the declaration, statistics, labels and number
formats, Markdown tables, the figures' look, the one CSV writer and the one psim runner."""
