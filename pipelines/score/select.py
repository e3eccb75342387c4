"""Choosing what to play from a notes table: a range of measures, one part or all."""

from __future__ import annotations

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError


def select_measures(notes: pd.DataFrame, start: int | None, end: int | None) -> pd.DataFrame:
    """Keep the notes from measure ``start`` to measure ``end`` (inclusive), re-timed to 0.

    Measure numbers restart in every movement; the first passage (in score order) whose
    measures fall in the range is taken.

    Raises
    ------
    ParameterError
        The range is empty or holds no notes.
    """
    if start is None and end is None:
        return notes
    lo = -np.inf if start is None else start
    hi = np.inf if end is None else end
    if lo > hi:
        raise ParameterError(f"--start-measure {start} is after --end-measure {end}")
    order = notes.sort_values("onset_beats", kind="stable")
    inside = (order["measure"] >= lo) & (order["measure"] <= hi)
    if not inside.any():
        raise ParameterError(f"no notes in measures {start}..{end} "
                             f"(the score has measures {notes['measure'].min()}.."
                             f"{notes['measure'].max()})")
    b0 = float(order.loc[inside, "onset_beats"].iloc[0])
    after = order[(order["onset_beats"] > b0) & ~inside]
    b1 = float(after["onset_beats"].iloc[0]) if len(after) else np.inf
    keep = notes[(notes["onset_beats"] >= b0) & (notes["onset_beats"] < b1)
                 & (notes["measure"] >= lo) & (notes["measure"] <= hi)].copy()
    t0 = float(keep["onset"].min())
    keep["onset"] = keep["onset"] - t0
    return keep.reset_index(drop=True)


def choose_parts(notes: pd.DataFrame, part: str | None, all_parts: bool) -> list[int]:
    """Part indices to render: ``--part NAME|INDEX``, every part, or the first.

    Raises
    ------
    ParameterError
        The part is not in the score (the message lists the parts).
    """
    table = notes.groupby("part_index", sort=True)[["part_name", "part_id"]].first()
    indices = [int(i) for i in table.index]
    if all_parts:
        if part is not None:
            raise ParameterError("give either --part or --all-parts, not both")
        return indices
    if part is None:
        return indices[:1]
    listing = ", ".join(f"{i}={table.loc[i, 'part_name']!r}" for i in indices)
    if part.strip().lstrip("-").isdigit():
        k = int(part)
        if 0 <= k < len(indices):
            return [indices[k]]
        raise ParameterError(f"--part {part} is out of range (parts: {listing})")
    key = part.strip().lower()
    for column in ("part_name", "part_id"):
        exact = [i for i in indices if str(table.loc[i, column]).lower() == key]
        if exact:
            return exact[:1]
    partial = [i for i in indices if key in str(table.loc[i, "part_name"]).lower()]
    if len(partial) == 1:
        return partial
    raise ParameterError(f"--part {part!r} matches {len(partial) or 'no'} parts "
                         f"(parts: {listing})")


def list_movements(notes: pd.DataFrame) -> pd.DataFrame:
    """The movements of a notes table: ``movement``, ``title``, first and last measure.

    Examples
    --------
    >>> notes = pd.DataFrame({"movement": [1, 1, 2], "movement_title": ["Allegro", "Allegro",
    ...                       None], "measure": [1, 40, 1]})
    >>> list_movements(notes).to_dict("records")[1]
    {'movement': 2, 'title': '', 'first_measure': 1, 'last_measure': 1}
    """
    movement = _movement(notes)
    frame = pd.DataFrame({"movement": movement, "title": notes["movement_title"].fillna("")
                          if "movement_title" in notes else "",
                          "measure": notes["measure"].to_numpy()})
    grouped = frame.groupby("movement", sort=True)
    out = pd.DataFrame({"title": grouped["title"].first(),
                        "first_measure": grouped["measure"].min(),
                        "last_measure": grouped["measure"].max()}).reset_index()
    return out.astype({"movement": int, "first_measure": int, "last_measure": int})


def select_movement(notes: pd.DataFrame, movement: int | None) -> pd.DataFrame:
    """Keep the notes of movement ``movement`` (from 1), re-timed to start at 0.

    ``None`` keeps a one-movement score whole and takes the first movement of a longer one.

    Raises
    ------
    ParameterError
        The score has no such movement (the message lists them).
    """
    numbers = _movement(notes)
    available = sorted({int(m) for m in numbers})
    if movement is None:
        if len(available) == 1:
            return notes
        movement = available[0]
    if movement not in available:
        raise ParameterError(f"--movement {movement}: the score has movement(s) "
                             f"{', '.join(str(m) for m in available)}")
    keep = notes[numbers == movement].copy()
    keep["onset"] = keep["onset"] - float(keep["onset"].min())
    keep["onset_beats"] = keep["onset_beats"] - float(keep["onset_beats"].min())
    return keep.reset_index(drop=True)


def _movement(notes: pd.DataFrame) -> np.ndarray:
    if "movement" not in notes:
        return np.ones(len(notes), dtype=np.int64)
    return pd.Series(notes["movement"]).fillna(1).to_numpy(dtype=np.int64)
