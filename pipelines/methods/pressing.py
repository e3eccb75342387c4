"""Pressing limits: the bow force above which a string of the instrument model sounds flat.

Pressed towards the top of its Helmholtz window a bowed string stays in Helmholtz motion
but its period lengthens: the pitch falls (the flattening effect). On this model the heavy
strings flatten early: the cello's G string bowed at beta 0.084 and 0.16 m/s in Helmholtz
motion sounds 5 cents flat at the middle of its window
(:func:`pipelines.methods.playable.window_middle`), 17 at 1.25 times it and 38 at 1.5 times
it, where the violin's strings stay within a few cents up to 1.75 times. The teacher calls
a hop more than 10 cents flat pressed (class 4), and the listening loop, which hears the
wispy side better than the flat one, pushed sampled cello notes up to the top of the
playable band. ``bench/calibrate_pressing.py`` measures, per instrument, string, bow
velocity and beta, the largest force (a multiple of the window's middle) below every one
that sounds flat; the table ships as ``pressing_limits.parquet`` beside this module
(:data:`data_schemas.pressing.PRESSING_LIMITS`). :func:`pressing_limit` reads it for one
instrument; gesture sampling's playable transform and its loop keep sampled forces under it
(:mod:`pipelines.methods.playable`), and so do the rules' notes
(:func:`pipelines.perform.note_shape.pressing_cap`).
"""

from __future__ import annotations

import hashlib
import warnings
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import RegularGridInterpolator

from data_schemas.errors import ParameterError

TABLE_PATH = Path(__file__).with_name("pressing_limits.parquet")
_ROOT = Path(__file__).resolve().parents[2]
_SOURCES = (_ROOT / "synth" / "config" / "strings.toml",
            _ROOT / "data_schemas" / "config" / "instruments.toml")
#: A limit never brings the band's top below the window's middle (the rules' lanes sit on it).
FLOOR = 1.0


def pressing_key() -> str:
    """Hash of what the pressing limits depend on: the string physics and instrument facts.

    Examples
    --------
    >>> len(pressing_key())
    16
    """
    h = hashlib.sha256()
    for path in _SOURCES:
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


@lru_cache(maxsize=4)
def load_pressing_limits(path: str | None = None) -> pd.DataFrame:
    """The pressing-limit table (validated; :data:`data_schemas.pressing.PRESSING_LIMITS`)."""
    from data_schemas.io import read_frame
    from data_schemas.pressing import PRESSING_LIMITS

    table = read_frame(path or TABLE_PATH, PRESSING_LIMITS)
    if len(table) and (table["key"] != pressing_key()).any():
        warnings.warn(f"{path or TABLE_PATH} was measured with other string physics or "
                      "instrument facts; run bench/calibrate_pressing.py", stacklevel=2)
    return table


class PressingLimit:
    """The pressing limit of one instrument's strings at any bowing.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :data:`data_schemas.pressing.PRESSING_LIMITS`.
    instrument : str

    Examples
    --------
    >>> limit = PressingLimit(load_pressing_limits(), "cello")
    >>> top = limit(np.array([1, 1]), np.array([0.16, 0.16]), np.array([0.084, 0.18]))
    >>> bool(top[0] < top[1])
    True
    """

    def __init__(self, table: pd.DataFrame, instrument: str):
        rows = table[table["instrument"] == instrument]
        if rows.empty:
            raise ParameterError(f"no pressing limits for instrument {instrument!r} (run "
                                 "bench/calibrate_pressing.py)")
        self._grids = {}
        for s, g in rows.groupby("string"):
            wide = g.pivot_table(index="bow_velocity", columns="beta", values="multiple")
            if wide.isna().any().any():
                raise ParameterError(f"the pressing limits of {instrument} string {s} have "
                                     "holes (run bench/calibrate_pressing.py)")
            speeds = np.log(wide.index.to_numpy(np.float64))
            betas = wide.columns.to_numpy(np.float64)
            self._grids[int(s)] = (RegularGridInterpolator((speeds, betas), wide.to_numpy()),
                                   speeds, betas)

    def __call__(self, string: np.ndarray, bow_velocity: np.ndarray,
                 beta: np.ndarray) -> np.ndarray:
        """Largest force (times the window's middle) that does not flatten, at least FLOOR.

        Parameters
        ----------
        string : np.ndarray [shape=(n,)], int
        bow_velocity : np.ndarray [shape=(n,)], m/s (its magnitude counts)
        beta : np.ndarray [shape=(n,)]

        Returns
        -------
        np.ndarray [shape=(n,)]
            Bilinear in log speed and beta inside the measured grid, its edge value outside.
        """
        string = np.asarray(string, int)
        v = np.log(np.maximum(np.abs(np.asarray(bow_velocity, np.float64)), 1e-3))
        b = np.asarray(beta, np.float64)
        out = np.full(string.shape, np.inf)
        for s, (interp, speeds, betas) in self._grids.items():
            m = string == s
            if m.any():
                points = np.column_stack([np.clip(v[m], speeds[0], speeds[-1]),
                                          np.clip(b[m], betas[0], betas[-1])])
                out[m] = interp(points)
        return np.maximum(out, FLOOR)


def pressing_limit(instrument: str, search_config: dict) -> PressingLimit | None:
    """The instrument's limit when the search settings' ``[render] pressing_limit`` names it.

    Examples
    --------
    >>> pressing_limit("violin", {"render": {"pressing_limit": []}}) is None
    True
    """
    if instrument not in search_config.get("render", {}).get("pressing_limit", []):
        return None
    return shipped_limit(instrument)


@lru_cache(maxsize=8)
def shipped_limit(instrument: str) -> PressingLimit:
    """The shipped table's limit, built once per process (every part and judged sample asks).

    Examples
    --------
    >>> shipped_limit("viola") is shipped_limit("viola")
    True
    """
    return PressingLimit(load_pressing_limits(), instrument)


__all__ = ["FLOOR", "PressingLimit", "TABLE_PATH", "load_pressing_limits", "pressing_key",
           "pressing_limit", "shipped_limit"]
