"""95% bootstrap confidence intervals of pooled scores, resampling frames.

Table 1's scores pool a few hundred objects, and objects of one frame (and of neighbouring frames)
are not independent, so the unit of resampling is the *frame*: a resample draws as many frames as
there are, with replacement, and recomputes the pooled score. Every score here is a ratio of sums
over frames, so each frame is summarised by two numbers (its numerator and denominator sums):

- ``IoU_mu`` = sum of the objects' IoUs / number of objects;
- ``P_mu`` = sum over objects of the share of thresholds ``x`` in 0.50..0.95 with ``IoU >= x``
  (:func:`p_scores`) / number of objects (= the mean of the ``P_x``, as in
  :func:`flic_cli.metrics.summarize`);
- ``PQ`` = sum of the TPs' IoUs / (TP + FP/2 + FN/2) (:mod:`flic_cli.metrics.panoptic`).

Conventions: scipy's :func:`scipy.stats.bootstrap` with ``paired=True`` (numerator and
denominator of a frame stay together), BCa intervals (bias-corrected and accelerated, scipy's
default; percentile intervals where BCa is undefined), 9999 resamples, a fixed seed (0), so the
same data gives the same interval on every run and machine. Frames whose denominator is 0 (no
object) carry no information on the ratio and are left out (otherwise a resample made only of
them would have no value). Degenerate cases: no frame with a denominator -> estimate and interval
NaN; one such frame -> the estimate, interval NaN (nothing to resample); every resample equal
(e.g. all frames identical) -> the zero-width interval ``(estimate, estimate)``.
"""

from __future__ import annotations

import inspect
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import stats

from flic_cli.metrics.instances import _IOU_SLACK, IOU_THRESHOLDS

__all__ = [
    "CONFIDENCE",
    "N_RESAMPLES",
    "SEED",
    "Interval",
    "frame_sums",
    "iou_mu_interval",
    "p_mu_interval",
    "p_scores",
    "pq_interval",
    "ratio_interval",
]

#: Confidence level of every interval.
CONFIDENCE: float = 0.95
#: Bootstrap resamples (scipy's default).
N_RESAMPLES: int = 9999
#: Seed of the resampling: intervals are reproducible.
SEED: int = 0

_MAX_BATCH_VALUES = 4_000_000  # resamples x frames held in memory at once
_RNG_KEYWORD = "rng" if "rng" in inspect.signature(stats.bootstrap).parameters else "random_state"


@dataclass(frozen=True)
class Interval:
    """A pooled ratio with its bootstrap confidence interval (same units as the ratio).

    Attributes
    ----------
    estimate : float
        The ratio of the sums over all frames (NaN when the denominators sum to 0).
    low, high : float
        Interval bounds (NaN when undefined, see the module docstring).
    frames : int
        Frames resampled (those with a non-zero denominator).
    """

    estimate: float
    low: float
    high: float
    frames: int


def _ratio(num: np.ndarray, den: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.sum(num, axis=axis) / np.sum(den, axis=axis)


def ratio_interval(
    numerators: np.ndarray,
    denominators: np.ndarray,
    confidence: float = CONFIDENCE,
    n_resamples: int = N_RESAMPLES,
    seed: int = SEED,
) -> Interval:
    """Bootstrap interval of ``sum(numerators) / sum(denominators)``, resampling frames.

    Parameters
    ----------
    numerators, denominators : numpy.ndarray
        ``(F,)`` per-frame sums (e.g. the IoU sum and the object count of each frame);
        denominators must be >= 0.
    confidence : float, default 0.95
        Confidence level.
    n_resamples : int, default 9999
        Bootstrap resamples.
    seed : int, default 0
        Seed of the resampling.

    Returns
    -------
    Interval

    Raises
    ------
    ValueError
        When the arrays are not 1-D of one length, or a denominator is negative or not finite.
    """
    num = np.asarray(numerators, dtype=np.float64)
    den = np.asarray(denominators, dtype=np.float64)
    if num.ndim != 1 or den.shape != num.shape:
        raise ValueError(f"expected two 1-D arrays of one length, got {num.shape}, {den.shape}")
    if not (np.isfinite(den).all() and (den >= 0).all() and np.isfinite(num).all()):
        raise ValueError("sums must be finite and denominators >= 0")
    used = den > 0
    num, den = num[used], den[used]
    nan = float("nan")
    if num.size == 0:
        return Interval(nan, nan, nan, 0)
    estimate = float(_ratio(num, den))
    if num.size == 1:
        return Interval(estimate, nan, nan, 1)
    common = {"paired": True, "vectorized": True, "confidence_level": confidence}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # degenerate distributions are handled below
        res = stats.bootstrap(
            (num, den),
            _ratio,
            n_resamples=n_resamples,
            batch=max(1, _MAX_BATCH_VALUES // num.size),
            method="BCa",
            **common,
            **{_RNG_KEYWORD: np.random.default_rng(seed)},
        )
        if np.ptp(res.bootstrap_distribution) <= 1e-12 * max(abs(estimate), 1.0):
            return Interval(estimate, estimate, estimate, int(num.size))
        low, high = res.confidence_interval
        if not (np.isfinite(low) and np.isfinite(high)):  # BCa undefined: percentile
            res = stats.bootstrap(
                (num, den),
                _ratio,
                n_resamples=0,
                bootstrap_result=res,
                method="percentile",
                **common,
            )
            low, high = res.confidence_interval
    return Interval(estimate, float(low), float(high), int(num.size))


def p_scores(ious: np.ndarray) -> np.ndarray:
    """Per-object contribution to ``P_mu``: the share of the thresholds 0.50..0.95 reached.

    Parameters
    ----------
    ious : numpy.ndarray
        ``(M,)`` per-object IoUs.

    Returns
    -------
    numpy.ndarray
        ``(M,)`` values in ``[0, 1]``; their mean is ``P_mu`` of :func:`flic_cli.metrics.summarize`
        (same slack of 1e-12).
    """
    iou = np.asarray(ious, dtype=np.float64).reshape(-1, 1)
    return (iou >= np.asarray(IOU_THRESHOLDS) - _IOU_SLACK).mean(axis=1)


def frame_sums(frame_keys: np.ndarray, ious: np.ndarray) -> dict[str, np.ndarray]:
    """Per-frame sums of a per-object table, the input of the intervals.

    Parameters
    ----------
    frame_keys : numpy.ndarray
        ``(M,)`` frame of each object (any hashable values with a total order, e.g. strings
        ``"08/000012"`` or integer indices).
    ious : numpy.ndarray
        ``(M,)`` per-object IoUs.

    Returns
    -------
    dict of str to numpy.ndarray
        ``frame`` (the distinct keys, sorted), ``iou_sum``, ``p_sum`` (sum of :func:`p_scores`)
        and ``objects``, each ``(F,)``.
    """
    keys = np.asarray(frame_keys)
    iou = np.asarray(ious, dtype=np.float64).reshape(-1)
    if keys.shape != iou.shape:
        raise ValueError(f"frame_keys and ious differ in shape: {keys.shape}, {iou.shape}")
    frames, inv = np.unique(keys, return_inverse=True)
    inv = inv.reshape(-1)
    return {
        "frame": frames,
        "iou_sum": np.bincount(inv, weights=iou, minlength=frames.size),
        "p_sum": np.bincount(inv, weights=p_scores(iou), minlength=frames.size),
        "objects": np.bincount(inv, minlength=frames.size).astype(np.int64),
    }


def iou_mu_interval(iou_sum: np.ndarray, objects: np.ndarray, **kwargs) -> Interval:
    """Interval of ``IoU_mu`` (fraction) from per-frame IoU sums and object counts.

    Keyword arguments go to :func:`ratio_interval`.
    """
    return ratio_interval(iou_sum, objects, **kwargs)


def p_mu_interval(p_sum: np.ndarray, objects: np.ndarray, **kwargs) -> Interval:
    """Interval of ``P_mu`` (fraction) from per-frame sums of :func:`p_scores` and counts.

    Keyword arguments go to :func:`ratio_interval`.
    """
    return ratio_interval(p_sum, objects, **kwargs)


def pq_interval(
    iou_sum: np.ndarray, tp: np.ndarray, fp: np.ndarray, fn: np.ndarray, **kwargs
) -> Interval:
    """Interval of ``PQ = IoU sum / (TP + FP/2 + FN/2)`` (fraction) from per-frame counts.

    Use it for one class (e.g. the class-agnostic thing class of
    :func:`flic_cli.metrics.panoptic.agnostic_panoptic_counts`). Keyword arguments go to
    :func:`ratio_interval`.
    """
    den = (
        np.asarray(tp, dtype=np.float64)
        + 0.5 * np.asarray(fp, dtype=np.float64)
        + 0.5 * np.asarray(fn, dtype=np.float64)
    )
    return ratio_interval(iou_sum, den, **kwargs)
