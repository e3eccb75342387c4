"""Slow, obviously correct twin of :mod:`synth.frames.viterbi_kernel`: every path tried."""

from __future__ import annotations

import itertools

import numpy as np


def naive_join_cost(i, j, features, successor, join_penalty):
    """0 for a frame's own successor, else the penalty plus the distance from i's successor."""
    if successor[i] == j:
        return 0.0
    ref = successor[i] if successor[i] >= 0 else i
    return join_penalty + float(np.linalg.norm(features[ref] - features[j]))


def naive_path_cost(path, cand, target_cost, features, successor, join_penalty):
    """Total cost of choosing column ``path[t]`` at every step ``t``."""
    total = sum(target_cost[t, c] for t, c in enumerate(path))
    for t in range(1, len(path)):
        total += naive_join_cost(cand[t - 1, path[t - 1]], cand[t, path[t]], features,
                                 successor, join_penalty)
    return total


def naive_viterbi_frames(cand, target_cost, features, successor, join_penalty):
    """(best path, its cost) by enumerating all N**T paths."""
    n_t, n_c = cand.shape
    best, best_path = np.inf, None
    for path in itertools.product(range(n_c), repeat=n_t):
        cost = naive_path_cost(path, cand, target_cost, features, successor, join_penalty)
        if cost < best:
            best, best_path = cost, np.array(path)
    return best_path, best


def naive_nearest_candidates(targets, features, centroids, labels, k, n):
    """The ``n`` nearest frames of each target within its ``k`` nearest clusters, by sorting.

    Every distance computed, clusters ranked by a stable sort (ties: lower centroid), the
    pool their members in ascending cluster then index order (all frames when it holds
    fewer than ``n``), candidates by a stable sort of the distances (ties: pool order),
    the last repeated when there are fewer than ``n``.
    """
    n_t = targets.shape[0]
    cand = np.zeros((n_t, n), np.int64)
    cost = np.zeros((n_t, n))
    for t in range(n_t):
        d_c = [float(np.sum((targets[t] - c) ** 2)) for c in centroids]
        near = sorted(sorted(range(len(d_c)), key=lambda c: d_c[c])[:k])
        pool = [j for c in near for j in range(len(labels)) if labels[j] == c]
        if len(pool) < n:
            pool = list(range(len(features)))
        d = [float(np.sqrt(np.sum((targets[t] - features[j]) ** 2))) for j in pool]
        best = sorted(range(len(pool)), key=lambda p: d[p])[:n]
        best += [best[-1]] * (n - len(best))
        cand[t] = [pool[p] for p in best]
        cost[t] = [d[p] for p in best]
    return cand, cost
