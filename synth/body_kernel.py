"""The spectral multiply-add of the partitioned body convolution (numba), behind a wrapper.

:func:`ring_multiply_add` is the entry point; its slow numpy twin is
``naive_ring_multiply_add`` in ``tests/naive_kernels.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from data_schemas.errors import ParameterError
from synth.array_checks import check_array


@njit(cache=True)
def _ring_multiply_add(ring, head, parts, out):  # pragma: no cover - numba
    """Sum over partitions p of ring[(head + p) % P] * parts[p], into ``out`` (spectra)."""
    n_parts = parts.shape[0]
    out[:] = 0.0
    for p in range(n_parts):
        row = ring[(head + p) % n_parts]
        part = parts[p]
        for k in range(out.size):
            out[k] += row[k] * part[k]


def ring_multiply_add(ring: np.ndarray, head: int, parts: np.ndarray) -> np.ndarray:
    """Sum of the spectra of a ring buffer times the partitions' spectra.

    ``out = sum_p ring[(head + p) % P] * parts[p]``: row ``head`` of the ring holds the
    newest input spectrum, which meets the first partition of the response.

    Parameters
    ----------
    ring : np.ndarray [shape=(P, n_bins)], complex128
        Input spectra (the frequency-domain delay line), newest at row ``head``.
    head : int
        Row of the newest spectrum, ``0..P-1``.
    parts : np.ndarray [shape=(P, n_bins)], complex128
        Spectra of the response's partitions, first partition first.

    Returns
    -------
    np.ndarray [shape=(n_bins,)], complex128

    Raises
    ------
    ParameterError
        Arrays of another dtype or shape, or ``head`` outside the ring.
    """
    check_array("ring", ring, np.complex128, 2)
    check_array("parts", parts, np.complex128, 2)
    if ring.shape != parts.shape:
        raise ParameterError(f"ring {ring.shape} and parts {parts.shape} must have one shape")
    if (isinstance(head, bool) or not isinstance(head, int | np.integer)
            or not 0 <= head < max(parts.shape[0], 1)):
        raise ParameterError(f"head must be a row of the ring (0..{parts.shape[0] - 1}), "
                             f"got {head!r}")
    out = np.empty(parts.shape[1], np.complex128)
    _ring_multiply_add(ring, head, parts, out)
    return out


__all__ = ["ring_multiply_add"]
