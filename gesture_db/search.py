"""Sample search: choose one database note per score note (Maestre et al. 2010, sec. 3.2).

For each target note (:data:`data_schemas.sampling.SAMPLING_TARGETS`) the candidates are the
database notes of its group; when the group is empty, those of the nearest compatible group
(a fallback, at a cost; a sample of the other bow direction is mirrored); with ``[fallback]
neighbours`` > 0 the groups within that distance compete too, at the same cost
(:func:`source_groups`, candidates merged by :mod:`gesture_db.search_candidates`). The
target cost of candidate q for note m is

    w_b (w_D |log2(D_m / D_q)| + w_le |log2(le_m / le_q)| + w_d |d_m - d_q| / span
         + w_s |s_m - s_q| / 3) + w_g Mahalanobis(f_pred_m, f_q; Sigma_G) / sqrt(k)
    + w_fb dist(G),

computed for all candidates of a group at once. The Mahalanobis distance is divided by the
square root of the feature dimension k (a typical sample of the group then costs about 1,
like a factor of two in duration), so groups of different k weigh alike; the ``n_best``
cheapest per note go to the Viterbi search (:mod:`gesture_db.search_kernel`), which adds
``w_b w_c`` times the continuity cost at every junction without a rest (L1 of the jumps
in velocity, force and beta between the end of one sample and the start of the next, in
units of ``continuity_scale``). Weights live in ``gesture_db/config/search.toml``
(:mod:`gesture_db.search_config`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from data_schemas.errors import ArcoError, ParameterError
from data_schemas.sampling import validate_choices, validate_targets
from gesture_db.groups import CONTOUR_PARAMS, grammar_for
from gesture_db.search_candidates import Candidates
from gesture_db.search_config import load_search_config
from gesture_db.search_kernel import path_cost, viterbi


class EmptyGroupsError(ArcoError):
    """No compatible database sample exists for some note groups of the score."""


# --------------------------------------------------------------------------- groups


def _parts(group: str) -> tuple[str, str, str, str]:
    t, d, s, r = (group.split("-") + ["", "", "", ""])[:4]
    return t, d, s, r


def group_distance(a: str, b: str, config: dict[str, Any]) -> float:
    """Distance between two note groups (0 for the same group), see ``[fallback]``."""
    if a == b:
        return 0.0
    fb = config["fallback"]
    ta, da, sa, ra = _parts(a)
    tb, db, sb, rb = _parts(b)
    dist = 0.0
    if ta != tb:
        table = fb["technique"]
        dist += float(table.get(f"{ta}-{tb}", table.get(f"{tb}-{ta}", fb["technique_default"])))
    dist += fb["direction"] * (da != db) + fb["slur_position"] * (sa != sb)
    dist += fb["run_position"] * (ra != rb)
    return dist


def resolve_groups(wanted: list[str], available: list[str],
                   config: dict[str, Any]) -> dict[str, tuple[str, float]]:
    """Map each wanted group to itself or to its nearest compatible available group.

    Returns
    -------
    dict
        ``wanted -> (group, distance)``; groups without a compatible one are left out.
    """
    out = {}
    limit = config["fallback"]["max_distance"]
    for g in wanted:
        if g in available:
            out[g] = (g, 0.0)
            continue
        scored = sorted((group_distance(g, a, config), a) for a in available)
        if scored and scored[0][0] <= limit:
            out[g] = (scored[0][1], scored[0][0])
    return out


# --------------------------------------------------------------------------- index


@dataclass(frozen=True)
class GroupIndex:
    """Arrays of one group's database notes for vectorised target costs.

    Attributes
    ----------
    note_id : np.ndarray [shape=(n,)], object
    duration : np.ndarray [shape=(n,)], s
    string_length : np.ndarray [shape=(n,)], m
    string : np.ndarray [shape=(n,)]
    dynamic : np.ndarray [shape=(n,)]
    features : np.ndarray [shape=(n, k)]
        PCA features f.
    whitened : np.ndarray [shape=(n, k)]
        ``f L^-T`` with ``Sigma_G = L L^T``, so Mahalanobis distances are Euclidean.
    whiten : np.ndarray [shape=(k, k)]
        ``L^-T``.
    feature_mean : np.ndarray [shape=(k,)]
    start, end : np.ndarray [shape=(n, 3)]
        Bezier velocity (m/s), force (N) and beta at the note's start and end.
    quality : np.ndarray [shape=(n,)] or None
        Quality cost of each sample from its practice renders (0 = every sustained hop in
        Helmholtz motion; see :func:`quality_costs`); None: not judged.
    """

    note_id: np.ndarray
    duration: np.ndarray
    string_length: np.ndarray
    string: np.ndarray
    dynamic: np.ndarray
    features: np.ndarray
    whitened: np.ndarray
    whiten: np.ndarray
    feature_mean: np.ndarray
    start: np.ndarray
    end: np.ndarray
    quality: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.note_id.size)


def edge_values(params: np.ndarray, group: str) -> tuple[np.ndarray, np.ndarray]:
    """Start and end values of velocity, force and beta from contour vectors.

    Parameters
    ----------
    params : np.ndarray [shape=(n, d)]
        Contour vectors p of one group.
    group : str
        The group (its grammar gives the layout of p).

    Returns
    -------
    start, end : np.ndarray [shape=(n, 3)]
    """
    grammar = grammar_for(group)
    starts, ends = [], []
    k = 0
    for param in CONTOUR_PARAMS:
        S = grammar.n_segments(param)
        starts.append(params[:, k + S])
        ends.append(params[:, k + 2 * S])
        k += 4 * S + 1
    return np.column_stack(starts), np.column_stack(ends)


def build_group_index(notes: pd.DataFrame, group: str, feature_mean: np.ndarray,
                      feature_cov: np.ndarray) -> GroupIndex:
    """Index the notes of one group (rows of the database notes table)."""
    F = np.vstack(notes["features"].to_numpy()).astype(np.float64)
    P = np.vstack(notes["params"].to_numpy()).astype(np.float64)
    L = np.linalg.cholesky(feature_cov)
    W = np.linalg.inv(L).T
    start, end = edge_values(P, group)
    return GroupIndex(
        note_id=notes["note_id"].to_numpy().astype(object),
        duration=notes["duration"].to_numpy(np.float64),
        string_length=notes["effective_string_length"].to_numpy(np.float64),
        string=notes["string"].to_numpy(np.float64),
        dynamic=notes["dynamic"].to_numpy(np.float64), features=F, whitened=F @ W, whiten=W,
        feature_mean=np.asarray(feature_mean, np.float64), start=start, end=end)


class SearchIndex:
    """Per-group arrays of a whole database, built once and reused for every search.

    Parameters
    ----------
    groups : dict of str to GroupIndex
    source : str
        Where the index came from (for messages).
    """

    def __init__(self, groups: dict[str, GroupIndex], source: str = "<index>") -> None:
        self.groups = groups
        self.source = source

    @classmethod
    def from_db(cls, db, *, instrument: str | None = None,
                quality: pd.DataFrame | None = None) -> SearchIndex:
        """Index a :class:`gesture_db.store.GestureDB`.

        Parameters
        ----------
        db : gesture_db.store.GestureDB
        instrument : str, optional
            Index only the notes played on this instrument (default all).
        quality : pandas.DataFrame, optional
            :data:`data_schemas.gesture_db.DB_QUALITY` rows: judged samples get their
            :func:`quality_costs`, the others the mean cost of the index's judged samples.
        """
        from gesture_db.store import model_from_row

        notes = db.notes()
        if instrument is not None:
            notes = notes[notes["instrument"] == instrument]
        cost = None if quality is None or not len(quality) else \
            pd.Series(quality_costs(quality),
                      index=quality["note_id"].to_numpy()).groupby(level=0).mean()
        if cost is not None:
            own = cost.reindex(notes["note_id"].to_numpy()).to_numpy(np.float64)
            fill = float(np.mean(own[np.isfinite(own)])) if np.isfinite(own).any() else 0.0
        models = db.models().set_index("group")
        groups = {}
        for group, rows in notes.groupby("group", sort=True):
            model = model_from_row(models.loc[group])
            gi = build_group_index(rows, str(group), model.feature_mean, model.feature_cov)
            if cost is not None:
                q = cost.reindex(gi.note_id).to_numpy(np.float64)
                gi = replace(gi, quality=np.where(np.isfinite(q), q, fill))
            groups[str(group)] = gi
        name = str(db.path) if instrument is None else f"{db.path} ({instrument})"
        return cls(groups, source=name)

    @property
    def n_notes(self) -> int:
        """Notes in the index."""
        return sum(len(g) for g in self.groups.values())


# --------------------------------------------------------------------------- search


@dataclass
class SearchResult:
    """The search's output.

    Attributes
    ----------
    choices : pandas.DataFrame
        :data:`data_schemas.sampling.SAMPLE_CHOICES`, one row per target.
    total_cost : float
        Cost of the chosen path.
    fallbacks : dict of str to str
        Wanted group -> group used, for the groups that fell back.
    """

    choices: pd.DataFrame
    total_cost: float
    fallbacks: dict[str, str]


def search(targets: pd.DataFrame, index: SearchIndex, *, predictors=None,
           config: dict[str, Any] | None = None) -> SearchResult:
    """Choose a database sample for every target note.

    Parameters
    ----------
    targets : pandas.DataFrame
        :data:`data_schemas.sampling.SAMPLING_TARGETS` rows in playing order.
    index : SearchIndex
        The database's per-group arrays.
    predictors : gesture_db.predict.Predictors, optional
        Per-group feature regressors; without them (or for a group without one) the
        predicted features are the group mean.
    config : dict, optional
        Search settings (:func:`load_search_config`); default the shipped ones.

    Returns
    -------
    SearchResult

    Raises
    ------
    EmptyGroupsError
        Some target groups have no compatible group in the database (names them).
    """
    from gesture_db.predict import context_features

    config = config or load_search_config()
    targets = validate_targets(targets)
    if len(targets) == 0:
        raise ParameterError("no target notes to search samples for")
    resolved = _resolve_or_raise(sorted(targets["group"].unique()), index, config)
    sources = source_groups(resolved, sorted(index.groups), config)
    n_best = int(min(config["n_best"], max(sum(len(index.groups[r]) for r, _ in src)
                                           for src in sources.values())))
    cands = Candidates.empty(len(targets), n_best)
    context = context_features(targets)
    group_col = targets["group"].to_numpy()
    for g, src in sources.items():
        rows = np.flatnonzero(group_col == g)
        for real, dist in src:
            _add_group(cands, targets, rows, context, g, real, dist, index, predictors, config)
    m = np.arange(len(targets))
    path, total, tc, cc = _best_path(cands, targets, config)
    chosen, used = cands.index[m, path], cands.used[m, path]
    choices = pd.DataFrame({
        "target_index": m.astype(np.int32),
        "note_id": [index.groups[used[i]].note_id[chosen[i]] for i in m],
        "group": group_col, "sample_group": used.astype(str),
        "mirrored": cands.mirrored[m, path],
        "sample_duration": [index.groups[used[i]].duration[chosen[i]] for i in m],
        "target_cost": tc, "continuity_cost": cc, "gesture_cost": cands.gesture[m, path]})
    fallbacks = {g: r for g, (r, d) in resolved.items() if r != g}
    return SearchResult(validate_choices(choices, source="search"), total, fallbacks)


def _add_group(cands: Candidates, targets: pd.DataFrame, rows: np.ndarray,
               context: np.ndarray, group: str, real: str, dist: float, index: SearchIndex,
               predictors, config: dict[str, Any]) -> None:
    """Merge the samples of group ``real`` into the candidates of ``group``'s notes ``rows``."""
    gi = index.groups[real]
    pred = predictors.predict(real, context[rows]) if predictors is not None else None
    if pred is None:
        pred = np.broadcast_to(gi.feature_mean, (rows.size, gi.feature_mean.size))
    flip = _parts(group)[1] != _parts(real)[1]
    base = config["weights"]["fallback"] * dist
    for chunk in _chunks(rows.size, len(gi)):
        cost, cg = _target_costs(targets.iloc[rows[chunk]], pred[chunk], gi, config)
        cands.keep(rows[chunk], cost + base, cg, gi, real, flip)


def source_groups(resolved: dict[str, tuple[str, float]], available: list[str],
                  config: dict[str, Any]) -> dict[str, list[tuple[str, float]]]:
    """The groups whose samples compete for each wanted group's notes, with distances.

    Each wanted group's own group (or its fallback, from :func:`resolve_groups`) first, then
    every other available group within ``[fallback] neighbours`` (and ``max_distance``);
    0 (off) keeps each note to its own group, as Maestre et al. (2010) search.

    Examples
    --------
    >>> from gesture_db.search_config import load_search_config
    >>> cfg = load_search_config()
    >>> cfg["fallback"]["neighbours"] = 0.25
    >>> have = ["legato-down-mid-mid", "legato-down-end-mid", "detache-down-iso-mid"]
    >>> source_groups({"legato-down-mid-mid": ("legato-down-mid-mid", 0.0)}, have, cfg)
    {'legato-down-mid-mid': [('legato-down-mid-mid', 0.0), ('legato-down-end-mid', 0.25)]}
    """
    reach = min(float(config["fallback"]["neighbours"]), config["fallback"]["max_distance"])
    out = {}
    for g, (real, dist) in resolved.items():
        near = [] if reach <= 0.0 else [
            (a, d) for a in available if a != real
            for d in [group_distance(g, a, config)] if 0.0 < d <= reach]
        out[g] = [(real, dist), *sorted(near, key=lambda x: (x[1], x[0]))]
    return out


def _resolve_or_raise(wanted: list[str], index: SearchIndex,
                      config: dict[str, Any]) -> dict[str, tuple[str, float]]:
    """:func:`resolve_groups` of the wanted groups, or an error naming those left out."""
    resolved = resolve_groups(wanted, sorted(index.groups), config)
    missing = [g for g in wanted if g not in resolved]
    if missing:
        have = ", ".join(sorted(index.groups)) or "none"
        raise EmptyGroupsError(
            f"{index.source}: no compatible samples for note group(s) {', '.join(missing)} "
            f"(the database has {have}; raise fallback.max_distance="
            f"{config['fallback']['max_distance']} or add recordings of these groups)")
    return resolved


def _best_path(cands: Candidates, targets: pd.DataFrame, config: dict[str, Any]):
    """Viterbi path over the candidates, its total cost and its per-note cost parts."""
    w = config["weights"]
    link = np.r_[False, targets["run_position"].isin(["mid", "end"]).to_numpy()[1:]]
    scale = np.array([config["continuity_scale"][p] for p in CONTOUR_PARAMS])
    w_c = w["basic"] * w["continuity"]
    path, total = viterbi(cands.target, cands.n_cand, cands.start, cands.end, link,
                          scale=scale, w_c=w_c)
    tc, cc = path_cost(cands.target, cands.start, cands.end, link, path, scale=scale, w_c=w_c)
    return path, total, tc, cc


def _chunks(n_rows: int, n_cand: int, budget: int = 2_000_000) -> list[slice]:
    """Row slices so that a chunk's cost matrix holds about ``budget`` entries."""
    step = max(1, budget // max(n_cand, 1))
    return [slice(a, min(a + step, n_rows)) for a in range(0, n_rows, step)]


def dynamic_costs(target: np.ndarray, sample: np.ndarray, span: float) -> np.ndarray:
    """Dynamic cost of samples for targets: ``|d_target - d_sample| / span``, uncapped.

    Maestre et al. (2010) give 0, 0.5 and 1 for zero, one and two levels apart, two levels
    being their database's whole range (p, mf, f). On the ten levels here (0 = pppp .. 9 =
    ffff) a cap at 1 made a pppp note cost the same with an ff sample as with an mf one, and
    the search took the longer ff sample for a long pianissimo (Beethoven op. 59/3 i, cello).

    Parameters
    ----------
    target, sample : np.ndarray
        Dynamic levels (0 = pppp .. 9 = ffff), broadcast against each other.
    span : float
        Levels apart for a cost of 1 (``[costs] dynamic_span``).

    Returns
    -------
    np.ndarray
        The costs, broadcast.

    Examples
    --------
    >>> dynamic_costs(np.array([[0.0]]), np.array([2.0, 5.0, 7.0]), 2.0)
    array([[1. , 2.5, 3.5]])
    """
    return np.abs(np.asarray(target, np.float64) - np.asarray(sample, np.float64)) / span


def _target_costs(t: pd.DataFrame, pred: np.ndarray, gi: GroupIndex,
                  config: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Weighted target cost (rows x candidates) and the unweighted gesture cost."""
    w = config["weights"]
    D = t["duration"].to_numpy(np.float64)[:, None]
    le = t["effective_string_length"].to_numpy(np.float64)[:, None]
    dyn = t["dynamic"].to_numpy(np.float64)[:, None]
    s = t["string"].to_numpy(np.float64)[:, None]
    basic = w["duration"] * np.abs(np.log2(D / gi.duration))
    basic += w["string_length"] * np.abs(np.log2(le / gi.string_length))
    basic += w["dynamic"] * dynamic_costs(dyn, gi.dynamic, config["costs"]["dynamic_span"])
    basic += w["string"] * np.abs(s - gi.string) / 3.0
    pw = np.asarray(pred, np.float64) @ gi.whiten
    d2 = (np.sum(pw**2, axis=1)[:, None] + np.sum(gi.whitened**2, axis=1)[None, :]
          - 2.0 * pw @ gi.whitened.T)
    cg = np.sqrt(np.maximum(d2, 0.0) / pw.shape[1])
    cost = w["basic"] * basic + w["gesture"] * cg
    if gi.quality is not None:
        cost = cost + w["quality"] * gi.quality[None, :]
    return cost, cg


def quality_costs(quality: pd.DataFrame) -> np.ndarray:
    """Quality cost of judged samples from their sustained hops' class histograms.

    The share of sustained hops not in Helmholtz motion (class 3) plus the share the teacher
    calls class 5 ("not a violin") again: 0 for a sample that sounds right throughout, 2 for
    one that never sounds like a string instrument.

    Parameters
    ----------
    quality : pandas.DataFrame
        ``class_counts`` (5 counts per sample, classes 1-5).

    Examples
    --------
    >>> q = pd.DataFrame({"class_counts": [[0, 0, 10, 0, 0], [0, 2, 6, 0, 2], [0, 0, 0, 0, 0]]})
    >>> quality_costs(q).round(3).tolist()
    [0.0, 0.6, 1.0]
    """
    counts = np.vstack(quality["class_counts"].to_numpy()).astype(np.float64)
    total = counts.sum(axis=1)
    good = np.where(total > 0, counts[:, 2] / np.maximum(total, 1), 0.0)
    bad5 = np.where(total > 0, counts[:, 4] / np.maximum(total, 1), 0.0)
    return 1.0 - good + bad5


__all__ = ["EmptyGroupsError", "GroupIndex", "SearchIndex", "SearchResult",
           "build_group_index", "dynamic_costs", "edge_values", "group_distance", "quality_costs",
           "resolve_groups", "search", "source_groups"]
