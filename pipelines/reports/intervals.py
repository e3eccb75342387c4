"""Figures with their spread: a two-stage bootstrap over seeds and notes, and who separates.

A method is rendered with several seeds; each seed's render of every excerpt gives a list
of per-note figures (:func:`pipelines.listening.evaluate.evaluate`). A figure's 95 %
interval is the percentile interval of a two-stage bootstrap: each replicate draws the
seeds with replacement and, within every drawn seed, its notes with replacement, then
computes the figure over the pooled drawn notes exactly as the yardstick does
(:func:`figures_of`). The spread therefore holds both what changes with the seed (the
friction noise, the performer's jitter) and what changes from note to note (the music).
The bootstrap is seeded (:data:`BOOTSTRAP_SEED`), so a report is reproducible. The reported
mean is the mean over seeds of each seed's figure.

Two methods *separate* on a figure when their intervals do not overlap; a method *wins* a
figure when it is the better side of a separation from every other method
(:func:`winner`). Figures where closer to zero is better (pitch and level errors) are
compared on their magnitude.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

#: Confidence level of the intervals.
LEVEL = 0.95
#: Bootstrap replicates.
N_BOOT = 1000
#: Seed of the bootstrap's random draws.
BOOTSTRAP_SEED = 20261201
#: Per-note columns :func:`note_arrays` keeps.
COLUMNS = ("sustained_hops", "helmholtz_share", "reached_helmholtz", "attack_ms",
           "pitch_error_cents_median", "level_error_db_median", "sus3", "sus5", "sus_total")


@dataclass(frozen=True)
class Interval:
    """A figure's mean over seeds and its bootstrap interval (NaN when undefined)."""

    mean: float
    low: float
    high: float

    def as_dict(self) -> dict[str, float]:
        """``{"mean", "low", "high"}``."""
        return {"mean": self.mean, "low": self.low, "high": self.high}


def note_arrays(notes: Sequence[Mapping[str, Any]]) -> dict[str, np.ndarray]:
    """Per-note figures as arrays (one entry per note, :data:`COLUMNS`).

    Examples
    --------
    >>> a = note_arrays([{"sustained_hops": 4, "helmholtz_share": 0.5,
    ...                   "reached_helmholtz": True, "attack_ms": 20.0,
    ...                   "pitch_error_cents_median": 1.0, "level_error_db_median": 0.0,
    ...                   "sustained_class_histogram": {"1": 0, "2": 0, "3": 3, "4": 0, "5": 1}}])
    >>> a["sus3"].tolist(), a["sus5"].tolist(), a["sus_total"].tolist()
    ([3.0], [1.0], [4.0])
    """
    def col(key: str) -> np.ndarray:
        return np.array([float(n[key]) for n in notes], np.float64)

    out = {k: col(k) for k in COLUMNS[:6]}
    hist = [n["sustained_class_histogram"] for n in notes]
    out["sus3"] = np.array([float(h["3"]) for h in hist], np.float64)
    out["sus5"] = np.array([float(h["5"]) for h in hist], np.float64)
    out["sus_total"] = np.array([float(sum(h.values())) for h in hist], np.float64)
    return out


def _ratio(num: np.ndarray, den: np.ndarray) -> float:
    d = den.sum()
    return float(num.sum() / d) if d > 0 else float("nan")


def _quantile(x: np.ndarray, q: float) -> float:
    x = x[np.isfinite(x)]
    return float(np.percentile(x, q)) if x.size else float("nan")


def figures_of(a: Mapping[str, np.ndarray], idx: np.ndarray | None = None) -> dict[str, float]:
    """The scored figures over the notes ``idx`` of ``a`` (all notes when None).

    The same definitions as :func:`pipelines.listening.evaluate.piece_figures` (a test
    holds them equal), plus the class-5 share of sustained hops.

    Examples
    --------
    >>> a = {k: np.array(v, float) for k, v in dict(
    ...     sustained_hops=[10, 30], helmholtz_share=[1.0, 0.5], reached_helmholtz=[1, 1],
    ...     attack_ms=[10.0, 30.0], pitch_error_cents_median=[1.0, 3.0],
    ...     level_error_db_median=[0.0, 0.0], sus3=[10, 10], sus5=[0, 10],
    ...     sus_total=[10, 30]).items()}
    >>> f = figures_of(a)
    >>> f["helmholtz_share"], f["sustained_class5_share"], f["attack_ms_median"]
    (0.625, 0.25, 20.0)
    """
    if idx is not None:
        a = {k: v[idx] for k, v in a.items()}
    share, sus = a["helmholtz_share"], a["sustained_hops"]
    ok = np.isfinite(share)
    n = a["reached_helmholtz"].size
    return {
        "helmholtz_share": _ratio(share[ok] * sus[ok], sus[ok]),
        "attack_ms_p90": _quantile(a["attack_ms"], 90),
        "sustained_class3_share": _ratio(a["sus3"], a["sus_total"]),
        "sustained_class5_share": _ratio(a["sus5"], a["sus_total"]),
        "reached_helmholtz_share": float(a["reached_helmholtz"].mean()) if n else float("nan"),
        "attack_ms_median": _quantile(a["attack_ms"], 50),
        "pitch_error_cents_median": _quantile(a["pitch_error_cents_median"], 50),
        "level_error_db_median": _quantile(a["level_error_db_median"], 50),
    }


def bootstrap(per_seed: Sequence[Mapping[str, np.ndarray]], *, n_boot: int = N_BOOT,
              level: float = LEVEL, seed: int = BOOTSTRAP_SEED) -> dict[str, Interval]:
    """Mean over seeds and two-stage bootstrap interval of every figure.

    Parameters
    ----------
    per_seed : sequence of dict
        One :func:`note_arrays` per seed (the notes of every excerpt that seed rendered).
    n_boot : int
        Replicates.
    level : float
        Confidence level (0.95: the 2.5 and 97.5 percentiles).
    seed : int
        Seed of the draws (same inputs and seed: the same intervals).

    Returns
    -------
    dict of str to Interval

    Examples
    --------
    >>> one = {k: np.ones(3) for k in COLUMNS}
    >>> bootstrap([one, one], n_boot=50)["helmholtz_share"]
    Interval(mean=1.0, low=1.0, high=1.0)
    """
    rng = np.random.default_rng(seed)
    sizes = [int(a["sustained_hops"].size) for a in per_seed]
    pooled = {k: np.concatenate([a[k] for a in per_seed]) for k in COLUMNS}
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    singles = [figures_of(a) for a in per_seed]
    names = list(singles[0]) if singles else []
    reps = np.full((n_boot, len(names)), np.nan)
    k = len(per_seed)
    for b in range(n_boot):
        seeds = rng.integers(0, k, k)
        idx = np.concatenate([starts[s] + rng.integers(0, max(sizes[s], 1), sizes[s])
                              for s in seeds] + [np.zeros(0, np.int64)])
        f = figures_of(pooled, idx)
        reps[b] = [f[n] for n in names]
    tail = 100.0 * (1.0 - level) / 2.0
    out = {}
    for j, name in enumerate(names):
        col = reps[:, j][np.isfinite(reps[:, j])]
        means = np.array([s[name] for s in singles])
        means = means[np.isfinite(means)]
        mean = float(means.mean()) if means.size else float("nan")
        if col.size:
            lo, hi = np.percentile(col, [tail, 100.0 - tail])
            out[name] = Interval(mean, float(lo), float(hi))
        else:
            out[name] = Interval(mean, float("nan"), float("nan"))
    return out


def oriented(iv: Interval, larger: bool | None) -> tuple[float, float, float]:
    """``(score, low, high)`` on a scale where larger is better.

    Closer-to-zero figures are compared on their magnitude: the interval of ``|x|``.

    Examples
    --------
    >>> oriented(Interval(2.0, 1.0, 3.0), False)
    (-2.0, -3.0, -1.0)
    >>> oriented(Interval(-1.0, -2.0, 0.5), None)
    (-1.0, -2.0, 0.0)
    """
    if larger:
        return iv.mean, iv.low, iv.high
    if larger is None:
        if iv.low <= 0.0 <= iv.high:
            mags = (0.0, max(-iv.low, iv.high))
        else:
            mags = tuple(sorted((abs(iv.low), abs(iv.high))))
        return -abs(iv.mean), -mags[1], 0.0 - mags[0] + 0.0
    return -iv.mean, -iv.high, -iv.low


def better(a: Interval, b: Interval, larger: bool | None) -> bool:
    """``a`` is separated from ``b`` on the better side (intervals do not overlap).

    Examples
    --------
    >>> better(Interval(0.9, 0.85, 0.95), Interval(0.7, 0.6, 0.8), True)
    True
    >>> better(Interval(0.9, 0.75, 0.95), Interval(0.7, 0.6, 0.8), True)
    False
    """
    sa, la, _ = oriented(a, larger)
    sb, _, hb = oriented(b, larger)
    return bool(np.isfinite(la) and np.isfinite(hb) and la > hb)


def winner(intervals: Mapping[str, Interval], larger: bool | None) -> str | None:
    """The method separated on the better side from every other, else None.

    Examples
    --------
    >>> winner({"a": Interval(0.9, 0.85, 0.95), "b": Interval(0.7, 0.6, 0.8)}, True)
    'a'
    >>> winner({"a": Interval(0.9, 0.7, 0.95), "b": Interval(0.7, 0.6, 0.8)}, True) is None
    True
    """
    if len(intervals) < 2:
        return None
    for m, iv in intervals.items():
        if all(better(iv, other, larger) for o, other in intervals.items() if o != m):
            return m
    return None


def contenders(intervals: Mapping[str, Interval], larger: bool | None) -> list[str]:
    """The best method by mean and every method not separated from it, best first.

    Examples
    --------
    >>> contenders({"a": Interval(0.9, 0.7, 0.95), "b": Interval(0.7, 0.6, 0.8),
    ...             "c": Interval(0.2, 0.1, 0.3)}, True)
    ['a', 'b']
    """
    finite = {m: iv for m, iv in intervals.items() if np.isfinite(iv.mean)}
    if not finite:
        return []
    order = sorted(finite, key=lambda m: -oriented(finite[m], larger)[0])
    best = finite[order[0]]
    return [order[0]] + [m for m in order[1:] if not better(best, finite[m], larger)]


__all__ = ["BOOTSTRAP_SEED", "COLUMNS", "LEVEL", "N_BOOT", "Interval", "better", "bootstrap",
           "contenders", "figures_of", "note_arrays", "oriented", "winner"]
