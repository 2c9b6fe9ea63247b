"""Step detection over a metric's history (make regress): binary segmentation of a mean shift.

A single comparison against the baseline misses a step smaller than its threshold, and one
that hides in noise run by run; over many nightly runs the step stands out. This is the
classic binary segmentation for changes in the mean: split the series where the sum of squared
deviations drops most, keep the split if the drop beats a penalty of `penalty` x sigma^2 x
log(n) (a BIC-like cost per change), and recurse into both halves. O(n^2) at worst, for
histories of a few hundred points a millisecond.

sigma is estimated robustly from first differences (a step is one outlier among them), with a
floor of `rel_floor` x the median level so a deterministic series (instruction counts) only
reports steps larger than what its measured spread allows.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Step:
    index: int      # first point of the new level
    before: float   # mean of the segment before
    after: float    # mean of the segment after

    @property
    def change(self) -> float:
        return self.after / self.before - 1 if self.before else float("inf")


def noise_sigma(values: np.ndarray) -> float:
    """Standard deviation of the noise from the MAD of first differences (1.4826 makes a MAD a
    standard deviation for Gaussian noise; a difference has twice the variance)."""
    if values.size < 3:
        return 0.0
    diff = np.diff(values)
    return 1.4826 * float(np.median(np.abs(diff - np.median(diff)))) / np.sqrt(2)


def _split_gain(prefix: np.ndarray, prefix_sq: np.ndarray, a: int, b: int, min_size: int):
    """Best split k of values[a:b] and the drop in squared error it buys."""
    def cost(i, j):
        n = j - i
        s = prefix[j] - prefix[i]
        return (prefix_sq[j] - prefix_sq[i]) - s * s / n

    whole = cost(a, b)
    best_k, best_gain = None, 0.0
    for k in range(a + min_size, b - min_size + 1):
        gain = whole - cost(a, k) - cost(k, b)
        if gain > best_gain:
            best_k, best_gain = k, gain
    return best_k, best_gain


def change_points(values, min_size: int = 3, penalty: float = 4.0,
                  rel_floor: float = 0.0) -> list[Step]:
    """Steps in the mean of `values` (in order), each with the segment means around it."""
    y = np.asarray(values, dtype=float)
    n = y.size
    if n < 2 * min_size:
        return []
    # Centre first: the prefix sums of squares stay well conditioned for values like 1e9.
    level = float(np.median(y))
    z = y - level
    sigma = max(noise_sigma(z), rel_floor * abs(level))
    if sigma == 0.0:
        sigma = np.finfo(float).eps * max(abs(level), 1.0)
    beta = penalty * sigma * sigma * np.log(n)
    prefix = np.concatenate([[0.0], np.cumsum(z)])
    prefix_sq = np.concatenate([[0.0], np.cumsum(z * z)])

    cuts, pending = [], [(0, n)]
    while pending:
        a, b = pending.pop()
        k, gain = _split_gain(prefix, prefix_sq, a, b, min_size)
        if k is not None and gain > beta:
            cuts.append(k)
            pending += [(a, k), (k, b)]
    cuts.sort()
    bounds = [0] + cuts + [n]
    means = [float(y[bounds[i]:bounds[i + 1]].mean()) for i in range(len(bounds) - 1)]
    return [Step(cuts[i], means[i], means[i + 1]) for i in range(len(cuts))]
