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
