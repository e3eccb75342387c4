"""A gesture database opened for sampling: per-instrument search indexes, predictors, forces.

Each part is sampled from the notes played on its own instrument (the database records each
note's instrument). A database without that instrument's notes is a *transfer*: the part is
sampled from the violin's notes (or the first instrument the database holds) with a
warning, its targets' string lengths made violin-equivalent, and the forces rescaled to the
part's strings (:func:`adapt_forces`). When the database holds judged samples
(``arco db judge``), the search adds each sample's quality cost.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.actions import ACTIONS


@dataclass
class SamplingDatabase:
    """A gesture database opened for sampling: search index, predictors and contours.

    Build it once with :func:`open_database` and pass it to every render (the index and the
    predictors are the expensive part).

    Attributes
    ----------
    db : gesture_db.store.GestureDB
    index : gesture_db.search.SearchIndex
        All notes (any instrument).
    predictors, contours, search_config
        Feature regressors (or None), contour reader and search settings.
    quality : pandas.DataFrame or None
        The judged samples (:data:`data_schemas.gesture_db.DB_QUALITY`).
    left_hand : gesture_db.left_hand.LeftHandSource or None
        The notes' left-hand descriptions (None: the rules' left hand for every note).
    """

    db: Any
    index: Any
    predictors: Any
    contours: Any
    search_config: dict[str, Any]
    quality: pd.DataFrame | None = None
    left_hand: Any = None
    _by_instrument: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def instruments(self) -> list[str]:
        """Instruments whose notes the database holds."""
        return self.db.instruments

    def index_for(self, instrument: str) -> tuple[Any, str, str | None]:
        """The search index for a part of ``instrument``.

        Returns
        -------
        index : gesture_db.search.SearchIndex
        sampled_from : str
            The instrument whose notes the index holds.
        warning : str or None
            Set when the database holds no notes of ``instrument`` (a transfer).
        """
        from gesture_db.search import SearchIndex

        have = self.instruments
        source = instrument if instrument in have else ("violin" if "violin" in have
                                                        else have[0])
        if source not in self._by_instrument:
            self._by_instrument[source] = SearchIndex.from_db(self.db, instrument=source,
                                                              quality=self.quality)
        warning = None
        if source != instrument:
            warning = (f"the gesture database holds no {instrument} notes (it has "
                       f"{', '.join(have)}); the {instrument} part is sampled from the "
                       f"{source}'s notes with forces rescaled to the {instrument}'s strings "
                       f"(simulate {instrument} recordings with `arco simulate-recordings "
                       f"--instrument {instrument}` and rebuild)")
        return self._by_instrument[source], source, warning


def open_database(path: str | os.PathLike, *, search_config: str | os.PathLike | None = None,
                  predictors: bool = True, progress: bool = False) -> SamplingDatabase:
    """Open a gesture database for sampling.

    Parameters
    ----------
    path : path-like
        Database directory (``arco build-db``).
    search_config : path-like, optional
        TOML merged over ``gesture_db/config/search.toml``.
    predictors : bool
        Load the per-group feature regressors (fitted and saved beside the database on
        first use); False predicts each group's mean features.
    progress : bool
        Progress bar while fitting predictors.

    Raises
    ------
    SchemaError
        No database at ``path`` or one of another schema version.
    """
    from gesture_db.assemble import ContourSource
    from gesture_db.left_hand import LeftHandSource
    from gesture_db.predict import load_or_fit_predictors
    from gesture_db.search import SearchIndex
    from gesture_db.search_config import load_search_config
    from gesture_db.store import GestureDB

    db = GestureDB(path)
    pred = load_or_fit_predictors(db, progress=progress) if predictors else None
    quality = db.quality()
    return SamplingDatabase(db, SearchIndex.from_db(db, quality=quality), pred,
                            ContourSource(db), load_search_config(search_config), quality,
                            LeftHandSource(db))


def adapt_forces(actions: pd.DataFrame, instrument: str, search_config: dict[str, Any], *,
                 sampled_from: str = "violin") -> pd.DataFrame:
    """Rescale recorded bow forces to the instrument model's strings.

    Each of the model's strings has its own Helmholtz window (its ``reference_force``,
    measured at 0.3 m/s and beta 0.1). The simulated violinist bows every string at
    ``recorded_reference_force`` (``[render]`` of the search settings, N) at mezzo-forte;
    simulated violists and cellists bow string ``s`` at that times the ratio of their
    model's reference force to the violin's (``arco simulate-recordings``). So forces are
    multiplied per string by ``reference_force(instrument, s) / recorded(sampled_from, s)``
    with ``recorded(x, s) = recorded_reference_force * reference(x, s) / reference(violin,
    s)``: for a part sampled from its own instrument that is the violin's factor, for a
    transfer the part's strings over the violinist's force.

    Returns
    -------
    pandas.DataFrame
        A copy with rescaled ``bow_force`` (pluck rows untouched).
    """
    from synth.strings import reference_forces

    recorded = float(search_config.get("render", {}).get("recorded_reference_force", 0.0))
    if recorded <= 0.0:
        return actions
    out = actions.copy()
    bowed = ~out["pluck"].to_numpy(bool)
    strings = out["string"].to_numpy(int)
    played = recorded * reference_forces(sampled_from) / reference_forces("violin")
    factor = reference_forces(instrument)[strings] / played[strings]
    out.loc[bowed, "bow_force"] = np.clip(out.loc[bowed, "bow_force"] * factor[bowed], 0.0,
                                          ACTIONS.column("bow_force").maximum)
    return out


__all__ = ["SamplingDatabase", "adapt_forces", "open_database"]
