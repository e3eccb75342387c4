"""Note groups and the Bezier contour grammar of each group.

A note group is technique x bow direction x slur position x run position (Maestre 2010),
named ``"<technique>-<direction>-<slur position>-<run position>"``. Its grammar gives, per
bowing parameter, the cubic Bezier segments of the contour, each with a slope constraint:
``"free"``, ``"flat_start"`` (zero slope at its start), ``"flat_end"`` or ``"flat"`` (both).
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pandas as pd

#: Parameters modelled by contours, in the order of the contour vector.
CONTOUR_PARAMS = ("bow_velocity", "bow_force", "beta")
#: Slope-constraint codes and their (start flat, end flat) flags.
CONSTRAINTS = {"free": (0, 0), "flat_start": (1, 0), "flat_end": (0, 1), "flat": (1, 1)}

_F3 = ("free", "free", "free")
_F2 = ("free", "free")
_GRAMMARS: dict[str, dict[str, tuple[str, ...]]] = {
    # rise from the bow change (or rest), sustain, fall into the next bow change
    "detache": {"bow_velocity": _F3, "bow_force": _F3, "beta": _F2},
    "legato": {"bow_velocity": _F3, "bow_force": _F3, "beta": _F2},
    # burst up, burst down, bow at rest (flat at zero)
    "staccato": {"bow_velocity": ("free", "free", "flat"), "bow_force": _F3, "beta": _F2},
    # force before motion, sharp attack, decay, release
    "martele": {"bow_velocity": ("free", "free", "flat_end"), "bow_force": _F3, "beta": _F2},
    # one bounce: speed up and down; force off, contact bump, off
    "spiccato": {"bow_velocity": ("free", "free"), "bow_force": ("flat", "free", "free"),
                 "beta": ("free",)},
}
# inside a slur the stroke continues: fewer segments
_LEGATO_MID = {"bow_velocity": _F2, "bow_force": _F2, "beta": _F2}


def group_name(technique: str, direction: str, slur_position: str, run_position: str) -> str:
    """Return the group name ``"<technique>-<direction>-<slur>-<run>"``."""
    return f"{technique}-{direction}-{slur_position}-{run_position}"


def chain_positions(linked_before: np.ndarray, linked_after: np.ndarray) -> np.ndarray:
    """Position of each note in a chain (a slur, a run without rests).

    Parameters
    ----------
    linked_before, linked_after : np.ndarray [shape=(n,)], bool
        The note is joined to the previous / next note.

    Returns
    -------
    np.ndarray [shape=(n,)], object
        ``init``, ``mid``, ``end`` or ``iso``.
    """
    out = np.full(linked_before.size, "iso", dtype=object)
    out[~linked_before & linked_after] = "init"
    out[linked_before & linked_after] = "mid"
    out[linked_before & ~linked_after] = "end"
    return out


def group_names(notes: pd.DataFrame) -> pd.Series:
    """Group names of a table with technique, bow_direction, slur and run positions."""
    return (notes["technique"].astype(str) + "-" + notes["bow_direction"].astype(str) + "-"
            + notes["slur_position"].astype(str) + "-" + notes["run_position"].astype(str))


@dataclass(frozen=True)
class Grammar:
    """Segments and slope constraints per contour parameter.

    Parameters
    ----------
    segments : dict of str to tuple of str
        For each of :data:`CONTOUR_PARAMS`, one constraint code per cubic segment.
    """

    segments: dict[str, tuple[str, ...]]

    def n_segments(self, param: str) -> int:
        """Number of cubic segments of ``param``."""
        return len(self.segments[param])

    def flags(self, param: str) -> np.ndarray:
        """Slope flags of ``param``, shape (n_segments, 2): start flat, end flat."""
        return np.array([CONSTRAINTS[c] for c in self.segments[param]], dtype=np.int64)

    @property
    def dim(self) -> int:
        """Length of the contour vector: per parameter 4 n + 1 numbers."""
        return sum(4 * self.n_segments(p) + 1 for p in CONTOUR_PARAMS)

    def value_mask(self) -> np.ndarray:
        """Which entries of the contour vector are segment end values.

        The rest are duration shares and handle ratios; the layout per parameter is
        ``shares (n), values (n + 1), handles (2n)``.

        Examples
        --------
        >>> g = Grammar({"bow_velocity": ("f",), "bow_force": ("f",), "beta": ("f",)})
        >>> g.value_mask().astype(int).tolist()[:5]
        [0, 1, 1, 0, 0]
        """
        out = []
        for param in CONTOUR_PARAMS:
            n = self.n_segments(param)
            out += [False] * n + [True] * (n + 1) + [False] * (2 * n)
        return np.array(out, bool)

    def blocks(self) -> np.ndarray:
        """Block label of each entry of the contour vector: parameter x kind.

        The kinds are duration shares (0), segment values (1, in the parameter's unit) and
        handle ratios (2); the label is ``3 * parameter index + kind``.

        Examples
        --------
        >>> g = Grammar({"bow_velocity": ("f",), "bow_force": ("f",), "beta": ("f",)})
        >>> g.blocks().tolist()[:6]
        [0, 1, 1, 2, 2, 3]
        """
        out: list[int] = []
        for k, param in enumerate(CONTOUR_PARAMS):
            n = self.n_segments(param)
            out += [3 * k] * n + [3 * k + 1] * (n + 1) + [3 * k + 2] * (2 * n)
        return np.array(out, np.int64)

    def to_json(self) -> str:
        """Serialise as JSON."""
        return json.dumps({p: list(self.segments[p]) for p in CONTOUR_PARAMS})

    @classmethod
    def from_json(cls, text: str) -> Grammar:
        """Inverse of :meth:`to_json`."""
        raw = json.loads(text)
        return cls({p: tuple(raw[p]) for p in CONTOUR_PARAMS})


def grammar_for(group: str) -> Grammar:
    """The contour grammar of a note group (unknown techniques use the detache grammar)."""
    technique, _direction, slur, _run = (group.split("-") + ["", "", "", ""])[:4]
    if technique == "legato" and slur == "mid":
        return Grammar(dict(_LEGATO_MID))
    return Grammar(dict(_GRAMMARS.get(technique, _GRAMMARS["detache"])))


__all__ = ["CONSTRAINTS", "CONTOUR_PARAMS", "Grammar", "grammar_for", "group_name",
           "group_names"]
