"""Sampled notes catch the string with the rules' bite (a transform into the playable space).

The simulated performers of the gesture database hold their force through a bow change
and onto a new string. On this model a stroke set on the string at a middling force
lands in multiple slipping that can last the whole of a short note (README, "How the
start decides the regime"); the rules therefore catch the string: each note that starts
a stroke, or crosses to a string, gets its force times ``bite_force`` for ``bite_hold``
s, released over ``bite_time`` s (:func:`pipelines.perform.note_shape.bite`,
``[articulations]`` of the rules' configuration). :func:`bite_samples` does the same to
sampled gestures, as a transform of the samples into the model's playable space (Maestre
et al. 2010), for the instruments listed in ``[render] bite`` of the search settings;
which notes caught the string is recorded in the sample choices (``bite``).

Examples
--------
>>> t = np.arange(0.0, 0.5, 0.01)
>>> acts = pd.DataFrame({"time": t, "string": 1, "bow_force": 1.0, "pluck": False})
>>> tgt = pd.DataFrame({"onset": [0.0, 0.25], "duration": [0.25, 0.25], "string": [1, 1],
...                     "slur_position": ["iso", "iso"]})
>>> cfg = {"articulations": {"bite_force": 1.3, "bite_hold": 0.1, "bite_time": 0.05}}
>>> out, caught = bite_samples(acts, tgt, [None, None], cfg)
>>> caught.tolist(), out["bow_force"].iloc[[0, 20, 25]].round(2).tolist()
([True, True], [1.3, 1.04, 1.3])
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS
from pipelines.perform.note_shape import bite


def catching_notes(targets: pd.DataFrame, bowed: list[Any]) -> np.ndarray:
    """Which target notes catch the string, as the rules' do.

    Parameters
    ----------
    targets : pandas.DataFrame
        The sampling targets (``string``, ``slur_position``; one row per bowed event).
    bowed : list
        Their events (None: a plain note); a grace note or a note under an ornament is not
        caught (a light bow, as in the rules).

    Returns
    -------
    np.ndarray [shape=(len(targets),)], bool
        True where the note starts a stroke (not inside a slur) or changes string.
    """
    string = targets["string"].to_numpy(int)
    starts = ~targets["slur_position"].isin(["mid", "end"]).to_numpy()
    crosses = np.r_[True, string[1:] != string[:-1]]
    plain = np.array([e is None or (e.ornament is None and not e.grace) for e in bowed], bool)
    return (starts | crosses) & plain


def bite_samples(actions: pd.DataFrame, targets: pd.DataFrame, bowed: list[Any],
                 config: dict[str, Any]) -> tuple[pd.DataFrame, np.ndarray]:
    """Sampled actions whose catching notes bite, and which notes bit.

    Parameters
    ----------
    actions : pandas.DataFrame
        Assembled actions of one part (:data:`data_schemas.actions.ACTIONS` columns
        ``time``, ``string``, ``bow_force``, ``pluck``).
    targets : pandas.DataFrame
        The sampling targets (``onset`` s, ``duration`` s, ``string``, ``slur_position``).
    bowed : list
        The targets' events (:func:`catching_notes`).
    config : dict
        Rules configuration (``[articulations] bite_force``, ``bite_hold``, ``bite_time``).

    Returns
    -------
    actions : pandas.DataFrame
        A copy in which each catching note's bowed rows on its string, from its onset to
        its end, carry the force times :func:`pipelines.perform.note_shape.bite` (clipped
        to the table's maximum); other rows untouched.
    caught : np.ndarray [shape=(len(targets),)], bool
        The notes that bit (all False when ``bite_force`` is 1).
    """
    caught = catching_notes(targets, bowed)
    if config["articulations"]["bite_force"] == 1.0:
        return actions, np.zeros(len(targets), bool)
    out = actions.copy()
    t = actions["time"].to_numpy(np.float64)
    force = actions["bow_force"].to_numpy(np.float64).copy()
    bowed_rows = ~actions["pluck"].to_numpy(bool) & (force > 0)
    onset = targets["onset"].to_numpy(np.float64)
    end = onset + targets["duration"].to_numpy(np.float64)
    string = targets["string"].to_numpy(int)
    row_string = actions["string"].to_numpy(int)
    for s in np.unique(string[caught]):
        rows = np.flatnonzero(bowed_rows & (row_string == s))
        rows = rows[np.argsort(t[rows], kind="stable")]
        for i in np.flatnonzero(caught & (string == s)):
            lo, hi = np.searchsorted(t[rows], [onset[i], end[i]], side="left")
            mine = rows[lo:hi]
            force[mine] *= bite(t[mine], float(onset[i]), config)
    out["bow_force"] = np.minimum(force, ACTIONS.column("bow_force").maximum)
    return out, caught


def bite_on(search_config: dict, instrument: str) -> bool:
    """Whether ``instrument``'s sampled notes bite (listed in ``[render] bite``).

    The list is checked once, when the search settings are loaded
    (:func:`gesture_db.search_config.load_search_config`).
    """
    return instrument in search_config.get("render", {}).get("bite", [])


def bite_chosen(actions: pd.DataFrame, targets: pd.DataFrame, choices: pd.DataFrame,
                bowed: list[Any], config: dict[str, Any], search_config: dict,
                instrument: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """:func:`bite_samples` when ``[render] bite`` lists ``instrument``.

    Returns the actions (unchanged when off) and a copy of ``choices`` whose ``bite`` says
    which notes bit (all False when off).
    """
    choices = choices.copy()
    caught = np.zeros(len(targets), bool)
    if bite_on(search_config, instrument):
        actions, caught = bite_samples(actions, targets, bowed, config)
    choices["bite"] = caught[choices["target_index"].to_numpy(int)]
    return actions, choices


__all__ = ["bite_chosen", "bite_on", "bite_samples", "catching_notes"]
