"""Argument checks of the kernel wrappers: one clear :class:`ParameterError` per bad array.

Numba kernels read their arrays without bounds checks, so a wrong shape or dtype there gives
garbage or a crash instead of an error; the ``*_kernel.py`` wrappers check with these first.
"""

from __future__ import annotations

import numpy as np

from data_schemas.errors import ParameterError


def check_array(name: str, value: object, dtype: type | np.dtype, ndim: int) -> np.ndarray:
    """Return ``value`` if it is a numpy array of ``dtype`` with ``ndim`` dimensions.

    Parameters
    ----------
    name : str
        The argument's name, for the error message.
    value : object
        The argument.
    dtype : numpy dtype
        The exact dtype required (no conversion: outputs are written in place).
    ndim : int
        The number of dimensions required.

    Returns
    -------
    np.ndarray
        ``value`` itself.

    Raises
    ------
    ParameterError
        ``value`` is not an array, or has another dtype or number of dimensions.
    """
    if not isinstance(value, np.ndarray):
        raise ParameterError(f"{name} must be a numpy array, got {type(value).__name__}")
    if value.ndim != ndim:
        raise ParameterError(f"{name} must be {ndim}-d, got shape {value.shape}")
    if value.dtype != np.dtype(dtype):
        raise ParameterError(f"{name} must hold {np.dtype(dtype)}, got {value.dtype}")
    return value


def check_size(name: str, value: np.ndarray, size: int, what: str) -> None:
    """Raise :class:`ParameterError` unless ``value`` holds ``size`` elements (``what``)."""
    if value.size != size:
        raise ParameterError(f"{name} must hold {size} elements ({what}), got {value.size}")
