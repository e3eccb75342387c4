"""Sampled contact points kept where this model's strings start cleanly (a playable transform).

Bowed from an abrupt start at forces inside its Helmholtz window, the modal string lands in
Helmholtz motion or in multiple slipping depending on the contact point
(``bench/contact_point.py``; README, "Where the contact point lets a string start"): the
violin's and viola's strings start cleanly at beta 0.08-0.13 and slip twice a period in
about half of the starts at beta 0.165-0.2, whatever the force; the cello's are cleanest
around beta 0.13. The simulated performers of the gesture database bow soft notes far from
the bridge (beta up to 0.2), where that regime then lasts the note.

:func:`into_beta_range` moves each bowed frame's beta into the instrument's range
``[render.beta_range]`` of the search settings, as a transform of the samples into the
playable space (Maestre et al. 2010), and keeps what the sample meant:

- the bow velocity is scaled by the same factor ``r = beta' / beta``, so ``v / beta`` (the
  Helmholtz amplitude, so the loudness) stays;
- the bow force by ``r^-0.5``, so its ratio to the middle of the window
  (:func:`pipelines.methods.playable.window_middle`, ``F_ref (v / 0.3) (0.1 / beta)^1.5``)
  stays;
- the bow position follows the new velocity (each frame's step times its ``r``).

The factor of each note (the median over its bowed frames) is recorded in the sample
choices (``beta_factor``).

Examples
--------
>>> acts = pd.DataFrame({"time": [0.0, 0.1], "string": 1, "bow_velocity": 0.2,
...                      "bow_force": 1.0, "beta": [0.1, 0.2], "bow_position": [0.5, 0.52],
...                      "pluck": False})
>>> out, r = into_beta_range(acts, 0.0, 0.13)
>>> out["beta"].tolist(), out["bow_velocity"].round(3).tolist(), r.round(2).tolist()
([0.1, 0.13], [0.2, 0.13], [1.0, 0.65])
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS
from data_schemas.errors import ParameterError


def beta_range(search_config: dict, instrument: str) -> tuple[float, float] | None:
    """The instrument's ``[render.beta_range]`` as ``(low, high)``; None when it has none.

    A high of 0 reads as no upper bound (``inf``).

    Examples
    --------
    >>> beta_range({"render": {"beta_range": {"violin": [0.0, 0.13]}}}, "violin")
    (0.0, 0.13)
    >>> beta_range({"render": {"beta_range": {"violin": [0.0, 0.13]}}}, "cello") is None
    True
    """
    pair = search_config.get("render", {}).get("beta_range", {}).get(instrument)
    if pair is None or (pair[0] == 0.0 and pair[1] == 0.0):
        return None
    return float(pair[0]), float(pair[1]) if pair[1] > 0.0 else float("inf")


def _positions(actions: pd.DataFrame, r: np.ndarray) -> np.ndarray:
    """Bow positions whose steps follow the scaled velocity (per string, in time order)."""
    pos = actions["bow_position"].to_numpy(np.float64).copy()
    strings = actions["string"].to_numpy(int)
    times = actions["time"].to_numpy(np.float64)
    for s in np.unique(strings):
        rows = np.flatnonzero(strings == s)
        rows = rows[np.argsort(times[rows], kind="stable")]
        steps = np.diff(pos[rows]) * r[rows[1:]]
        pos[rows] = pos[rows[0]] + np.concatenate([[0.0], np.cumsum(steps)])
    return np.clip(pos, 0.0, 1.0)


def into_beta_range(actions: pd.DataFrame, low: float, high: float
                    ) -> tuple[pd.DataFrame, np.ndarray]:
    """Move every bowed frame's beta into ``[low, high]``, keeping loudness and force ratio.

    Parameters
    ----------
    actions : pandas.DataFrame
        Actions of one part (:data:`data_schemas.actions.ACTIONS`).
    low, high : float
        The range of beta (``high`` may be ``inf``).

    Returns
    -------
    actions : pandas.DataFrame
        A copy: bowed frames (not plucks) with ``beta' = clip(beta, low, high)``,
        ``bow_velocity x r``, ``bow_force x r^-0.5`` (``r = beta' / beta``; clipped to the
        table's maxima) and the bow position stepped by the new velocity; others untouched.
    r : np.ndarray [shape=(len(actions),)]
        Each frame's factor (1 where untouched).

    Raises
    ------
    ParameterError
        ``low`` above ``high`` or either outside 0..``inf``.

    Examples
    --------
    >>> a = pd.DataFrame({"time": [0.0], "string": 0, "bow_velocity": 0.1, "bow_force": 0.5,
    ...                   "beta": 0.2, "pluck": False})
    >>> out, r = into_beta_range(a, 0.0, 0.1)
    >>> float(out["beta"][0]), float(out["bow_velocity"][0]), round(float(out["bow_force"][0]), 4)
    (0.1, 0.05, 0.7071)
    """
    if not 0.0 <= low <= high:
        raise ParameterError(f"beta range [{low}, {high}]: need 0 <= low <= high")
    out = actions.copy()
    beta = actions["beta"].to_numpy(np.float64)
    moved = np.clip(beta, low, high)
    bowed = ~actions["pluck"].to_numpy(bool) & (beta > 0.0)
    r = np.where(bowed, moved / np.where(beta > 0.0, beta, 1.0), 1.0)
    if np.all(r == 1.0):
        return out, r
    out["beta"] = np.where(bowed, moved, beta)
    out["bow_velocity"] = np.clip(actions["bow_velocity"].to_numpy(np.float64) * r,
                                  -ACTIONS.column("bow_velocity").maximum,
                                  ACTIONS.column("bow_velocity").maximum)
    out["bow_force"] = np.minimum(actions["bow_force"].to_numpy(np.float64) / np.sqrt(r),
                                  ACTIONS.column("bow_force").maximum)
    if "bow_position" in out:
        out["bow_position"] = _positions(actions, r)
    return out, r


def to_beta_range(actions: pd.DataFrame, targets: pd.DataFrame, choices: pd.DataFrame,
                  instrument: str, search_config: dict) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`into_beta_range` with the instrument's ``[render.beta_range]``, recorded.

    Returns the actions (unchanged without a range) and a copy of ``choices`` whose
    ``beta_factor`` is each note's median factor over its bowed frames (1: as sampled).

    Examples
    --------
    >>> a = pd.DataFrame({"time": [0.0, 0.1], "string": 1, "bow_velocity": 0.2,
    ...                   "bow_force": 1.0, "beta": 0.2, "pluck": False})
    >>> tgt = pd.DataFrame({"onset": [0.0], "duration": [0.2]})
    >>> cfg = {"render": {"beta_range": {"viola": [0.0, 0.13]}}}
    >>> _, ch = to_beta_range(a, tgt, pd.DataFrame({"target_index": [0]}), "viola", cfg)
    >>> ch["beta_factor"].round(2).tolist()
    [0.65]
    """
    from pipelines.methods.playable import note_of_rows

    choices = choices.copy()
    bounds = beta_range(search_config, instrument)
    factors = np.ones(len(targets))
    if bounds is not None:
        actions, r = into_beta_range(actions, *bounds)
        note = note_of_rows(actions, targets)
        ours = note >= 0
        medians = pd.Series(r[ours]).groupby(note[ours]).median()
        factors[medians.index.to_numpy()] = medians.to_numpy()
    choices["beta_factor"] = factors[choices["target_index"].to_numpy(int)]
    return actions, choices


__all__ = ["beta_range", "into_beta_range", "to_beta_range"]
