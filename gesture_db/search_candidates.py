"""The candidate table of the sample search: the cheapest samples of every target note.

Each note's candidates may come from several note groups (its own, the fallback when its
own is empty, and its neighbours within ``[fallback] neighbours``); :meth:`Candidates.keep`
merges a group's samples into the table, keeping the ``N`` cheapest per note, sorted by
target cost with the unused slots (cost inf) last, as :func:`gesture_db.search_kernel.viterbi`
expects.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Candidates:
    """The cheapest samples of every target note (rows: notes, columns: candidates).

    Attributes
    ----------
    target, gesture : np.ndarray [shape=(M, N)]
        Weighted target cost (inf beyond ``n_cand``) and unweighted gesture cost.
    index : np.ndarray [shape=(M, N)], int
        Row of each candidate in its group's :class:`gesture_db.search.GroupIndex`.
    n_cand : np.ndarray [shape=(M,)], int
        Candidates per note.
    start, end : np.ndarray [shape=(M, N, 3)]
        Velocity (m/s, sign flipped when mirrored), force (N) and beta at each candidate's
        start and end.
    used : np.ndarray [shape=(M, N)], object
        Group each candidate is sampled from.
    mirrored : np.ndarray [shape=(M, N)], bool
        Whether each candidate is of the other bow direction.
    """

    target: np.ndarray
    gesture: np.ndarray
    index: np.ndarray
    n_cand: np.ndarray
    start: np.ndarray
    end: np.ndarray
    used: np.ndarray
    mirrored: np.ndarray

    @classmethod
    def empty(cls, n_notes: int, n_best: int) -> Candidates:
        """No candidates yet for ``n_notes`` notes of up to ``n_best`` candidates."""
        shape = (n_notes, n_best)
        return cls(np.full(shape, np.inf), np.zeros(shape), np.zeros(shape, np.int64),
                   np.zeros(n_notes, np.int64), np.zeros((*shape, 3)), np.zeros((*shape, 3)),
                   np.full(shape, "", object), np.zeros(shape, bool))

    def keep(self, rows: np.ndarray, cost: np.ndarray, cg: np.ndarray, gi, group: str,
             flip: bool) -> None:
        """Merge the samples of ``group`` (index ``gi``) into the notes ``rows``.

        ``cost`` and ``cg`` (rows x samples of the group) are the weighted target and the
        gesture costs; ``flip`` mirrors the samples' velocities (other bow direction). Each
        note keeps its ``N`` cheapest candidates over every group merged so far; ties keep
        the earlier candidate first.
        """
        N = self.target.shape[1]
        sign = np.array([-1.0, 1.0, 1.0]) if flip else np.ones(3)
        k = min(N, len(gi))
        best = np.argpartition(cost, k - 1, axis=1)[:, :k] if k < len(gi) else \
            np.broadcast_to(np.arange(k), (rows.size, k))
        order = np.take_along_axis(cost, best, axis=1).argsort(axis=1, kind="stable")
        best = np.take_along_axis(best, order, axis=1)
        new = {"target": np.take_along_axis(cost, best, axis=1),
               "gesture": np.take_along_axis(cg, best, axis=1), "index": best,
               "start": gi.start[best] * sign, "end": gi.end[best] * sign,
               "used": np.full(best.shape, group, object),
               "mirrored": np.full(best.shape, flip, bool)}
        merged = np.concatenate([self.target[rows], new["target"]], axis=1)
        keep = np.argsort(merged, axis=1, kind="stable")[:, :N]
        for name, fresh in new.items():
            both = np.concatenate([getattr(self, name)[rows], fresh], axis=1)
            pick = keep[..., None] if both.ndim == 3 else keep
            getattr(self, name)[rows] = np.take_along_axis(both, pick, axis=1)
        self.n_cand[rows] = np.minimum(self.n_cand[rows] + k, N)


__all__ = ["Candidates"]
