"""Slow, obviously correct numpy twins of the small synth kernels.

Twins of :mod:`synth.diagnostics_kernel`, :mod:`synth.body_kernel`,
:mod:`synth.decimate_kernel` and :mod:`synth.listening.svm_kernel`, written from the
definitions in their docstrings (runs of slipping samples, a sum over partitions, index
arithmetic of the polyphase branches, one-vs-one votes) rather than from the loops.
"""

from __future__ import annotations

import numpy as np

from synth.diagnostics_kernel import SLIP_ONSET_SPEED_RATIO
from synth.modal_kernel import OFF_STRING, SLIPPING


def naive_summarise_slips(stick_slip, slip_velocity, bow_velocity, counted):
    """(onsets, n_slip, n_contact, slip_sum, counted) from the runs of slipping samples."""
    slipping = stick_slip == SLIPPING
    fast = slipping & (slip_velocity >= SLIP_ONSET_SPEED_RATIO * np.abs(bow_velocity))
    starts = slipping & ~np.concatenate([[False], slipping[:-1]])
    run = np.cumsum(starts)  # run number of each slipping sample
    onsets, last_counted = [], False
    for r in np.unique(run[slipping]):
        samples = np.flatnonzero(slipping & (run == r))
        already = counted and samples[0] == 0  # the slip under way was counted before
        hits = samples[fast[samples]]
        if hits.size and not already:
            onsets.append(hits[0])
        last_counted = already or hits.size > 0
    counted_at_end = bool(slipping[-1] and last_counted) if stick_slip.size else bool(counted)
    return (np.array(onsets, np.int64), int(slipping.sum()),
            int((stick_slip != OFF_STRING).sum()), float(slip_velocity[slipping].sum()),
            counted_at_end)


def naive_ring_multiply_add(ring, head, parts):
    """sum_p ring[(head + p) % P] * parts[p]."""
    n_parts = parts.shape[0]
    return sum((ring[(head + p) % n_parts] * parts[p] for p in range(n_parts)),
               np.zeros(parts.shape[1], complex))


def naive_add_correlation(branch, segment, out):
    """out + [sum_q branch[q] segment[k + q] for k]."""
    m = branch.size
    return out + np.array([np.dot(branch, segment[k:k + m]) for k in range(out.size)])


def naive_polyphase_decimate(extended, factor, phases, shifts, starts, taps, n_out):
    """out[k] = sum_b sum_q taps_b[q] extended[(k + shifts[b] + q) factor + phases[b]]."""
    out = np.zeros(n_out)
    for k in range(n_out):
        for b in range(phases.size):
            for q, tap in enumerate(taps[starts[b]:starts[b + 1]]):
                out[k] += tap * extended[(k + shifts[b] + q) * factor + phases[b]]
    return out


def naive_svc_decisions(x, mean, scale, sv, gamma, dual, intercept, n_support):
    """One-vs-one decision values of libsvm's C-SVC (RBF) for one row, pairs in order."""
    z = (x - mean) / scale
    kernel = np.exp(-gamma * ((z - sv) ** 2).sum(axis=1))
    starts = np.concatenate([[0], np.cumsum(n_support)])
    n_class = len(n_support)
    decisions = []
    for i in range(n_class):
        for j in range(i + 1, n_class):
            own, other = slice(starts[i], starts[i + 1]), slice(starts[j], starts[j + 1])
            decisions.append(dual[j - 1, own] @ kernel[own] + dual[i, other] @ kernel[other]
                             + intercept[len(decisions)])
    return np.array(decisions)


def naive_svc_predict(decisions, labels):
    """The label with most one-vs-one votes (a pair's vote goes to i when its value > 0)."""
    n_class = len(labels)
    votes = np.zeros(n_class, int)
    pairs = [(i, j) for i in range(n_class) for j in range(i + 1, n_class)]
    for (i, j), value in zip(pairs, decisions, strict=True):
        votes[i if value > 0 else j] += 1
    return labels[np.argmax(votes)]  # ties: the first (lowest) class
