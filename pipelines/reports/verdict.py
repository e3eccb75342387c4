"""The comparison's verdict sentence and its "why": which notes fail, how, and where.

The verdict names, per scored figure, the method that separates from every other one
(:func:`pipelines.reports.intervals.winner`) or the methods that do not separate. The why
classifies every evaluated note of every render:

- it *fails* when its attack is slow (:data:`ATTACK_MS`, or never stable), its sustained
  hops are not steadily in Helmholtz motion (share below :data:`HELMHOLTZ`) or too many
  of them sound like no violin (class 5 above :data:`CLASS5`);
- its *context*, from the played events: ``attack`` (it starts from silence: the first
  note, or the first of a run after a rest); else how the bowing joins the note before
  (``bow change``: a new stroke; ``bow restart``: the same stroke after the bow stopped,
  as in portato; ``legato``: the same stroke with the bow moving, a finger change or a
  crossing under a slur) and ``string crossing`` (on another string than the note before,
  without a rest between); ``short note`` (played for less than :data:`SHORT_S`), ``double stop``
  (two or more strings at once) and ``dynamic change`` (at least :data:`DYNAMIC_STEP`
  dynamic levels from the note before). A note may have several contexts, or none
  (``other``: events without the stroke information).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from pipelines.reports.figures import FIGURES, LABELS
from pipelines.reports.intervals import Interval, better, contenders, winner

#: A note's attack (ms to stable Helmholtz motion) slower than this fails (the issue's target).
ATTACK_MS = 50.0
#: A note whose sustained hops are in Helmholtz motion less often than this fails.
HELMHOLTZ = 0.9
#: A note with more of its sustained hops judged class 5 than this fails.
CLASS5 = 0.1
#: Notes played for less than this are short, s.
SHORT_S = 0.15
#: A dynamic step (levels, 5 = mf) from the note before that counts as a dynamic change.
DYNAMIC_STEP = 1.0
#: A note belongs to the last event starting at most this long after it, s.
MATCH_S = 0.02
CONTEXTS = ("attack", "bow change", "bow restart", "legato", "string crossing",
            "short note", "double stop", "dynamic change", "other")
FAILURES = ("slow attack", "unsteady", "class 5")


def _join(words: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    words = list(words)
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _standings(summary: Mapping[str, Mapping[str, Interval]], figures: Mapping[str, bool | None],
               headline: Sequence[str]) -> tuple[dict, dict]:
    """Per headline figure: who beats whom, or who does not separate and who trails them.

    Returns ``wins``: (top methods, the rest) -> figure labels, and ``ties``: (methods not
    separated from the best, ((method left out, those of them it trails), ...)) -> labels.
    """
    wins: dict[tuple[tuple[str, ...], tuple[str, ...]], list[str]] = {}
    ties: dict[tuple[tuple[str, ...], tuple[tuple[str, tuple[str, ...]], ...]], list[str]] = {}
    for fig in headline:
        per = {m: iv for m, iv in summary.get(fig, {}).items() if np.isfinite(iv.mean)}
        if len(per) < 2:
            continue
        w = winner(per, figures[fig])
        top = [w] if w is not None else contenders(per, figures[fig])
        rest = tuple(m for m in per if m not in top)
        if rest and all(better(per[a], per[b], figures[fig]) for a in top for b in rest):
            wins.setdefault((tuple(m for m in per if m in top), rest), []).append(LABELS[fig])
        else:
            behind = tuple((b, tuple(a for a in per if a in top
                                     and better(per[a], per[b], figures[fig])))
                           for b in rest)
            ties.setdefault((tuple(m for m in per if m in top), behind),
                            []).append(LABELS[fig])
    return wins, ties


def verdict_sentence(summary: Mapping[str, Mapping[str, Interval]], *, n_excerpts: int,
                     n_seeds: int, figures: Mapping[str, bool | None] = FIGURES,
                     headline: Sequence[str] = ("helmholtz_share", "attack_ms_p90",
                                                "sustained_class3_share",
                                                "sustained_class5_share"),
                     instrument: str | None = None, n_databases: int = 1) -> str:
    """One sentence: who beats whom on the headline figures, and what does not separate.

    A method beats the others on a figure when its interval separates from every other
    method's; a group of methods that do not separate from one another beats the rest when
    each of them separates from each of the rest ("sampling and sampling-open beat rules
    and feedback"); otherwise the methods not separated from the best are named as not
    separating, and each method left out is named behind those of them it separates from
    ("(feedback behind rules)").

    Parameters
    ----------
    summary : dict
        figure -> method -> :class:`~pipelines.reports.intervals.Interval`.
    n_excerpts, n_seeds : int
    figures : dict
        Figure -> larger is better (None: closer to zero).
    headline : sequence of str
        The figures the sentence speaks of (in this order).
    instrument : str, optional
        The summary holds only this instrument's parts ("On the cello parts of ...").
    n_databases : int
        Gesture databases the sampling methods played on (named in the sentence when
        there are several).

    Examples
    --------
    >>> s = {"helmholtz_share": {"rules": Interval(0.9, 0.85, 0.95),
    ...                          "feedback": Interval(0.7, 0.6, 0.8)},
    ...      "attack_ms_p90": {"rules": Interval(90, 60, 120),
    ...                        "feedback": Interval(100, 80, 130)}}
    >>> import textwrap
    >>> print(textwrap.fill(verdict_sentence(s, n_excerpts=4, n_seeds=5), 80))
    On 4 excerpts x 5 seeds, rules beats feedback on Helmholtz share; rules and
    feedback do not separate on attack p90.
    >>> s["helmholtz_share"]["sampling"] = Interval(0.92, 0.88, 0.97)
    >>> print(textwrap.fill(verdict_sentence(s, n_excerpts=4, n_seeds=5), 80))
    On 4 excerpts x 5 seeds, rules and sampling beat feedback on Helmholtz share;
    rules and feedback do not separate on attack p90.
    >>> s["helmholtz_share"]["sampling"] = Interval(0.85, 0.75, 0.9)
    >>> print(textwrap.fill(verdict_sentence(s, n_excerpts=4, n_seeds=5), 80))
    On 4 excerpts x 5 seeds, rules and sampling do not separate on Helmholtz share
    (feedback behind rules); rules and feedback do not separate on attack p90.
    """
    wins, ties = _standings(summary, figures, headline)
    clauses = []
    for (top, others), figs in wins.items():
        verb = "beats" if len(top) == 1 else "beat"
        clauses.append(f"{_join(top)} {verb} {_join(others)} on {_join(figs)}")
    for (who, behind), figs in ties.items():
        trail = "; ".join(f"{b} behind {_join(a)}" for b, a in behind if a)
        clauses.append(f"{_join(who)} do not separate on {_join(figs)}"
                       + (f" ({trail})" if trail else ""))
    plural = "s" if n_seeds != 1 else ""
    head = f"On {n_excerpts} excerpt{'s' if n_excerpts != 1 else ''} x {n_seeds} seed{plural}"
    if n_databases > 1:
        head += f" (x {n_databases} gesture databases for sampling)"
    if instrument:
        head = f"On the {instrument} parts of {head[3:]}"
    if not clauses:
        return head + ", no figure could be compared (fewer than two methods measured)."
    return head + ", " + "; ".join(clauses) + "."


def matched_events(notes: Sequence[dict[str, Any]], events: pd.DataFrame) -> list[int]:
    """For each evaluated note, the row of the last event starting by its start + MATCH_S.

    ``events`` must be sorted by ``t0``; an empty table gives 0 for every note.

    Examples
    --------
    >>> matched_events([{"start": 0.0}, {"start": 0.55}], pd.DataFrame({"t0": [0.0, 0.5]}))
    [0, 1]
    """
    t0 = events["t0"].to_numpy(np.float64) if len(events) else np.zeros(0)
    return [max(int(np.searchsorted(t0, float(n["start"]) + MATCH_S, side="right")) - 1, 0)
            for n in notes]


def note_contexts(notes: Sequence[dict[str, Any]], events: pd.DataFrame) -> list[list[str]]:
    """The context tags of each evaluated note (see the module doc), from its part's events.

    ``events`` must be sorted by ``t0``.

    Examples
    --------
    >>> ev = pd.DataFrame({"t0": [0.0, 0.5, 0.6], "played_end": [0.45, 0.58, 1.0],
    ...                    "string": [2, 2, 1], "dynamic": [5.0, 5.0, 7.0],
    ...                    "n_strings": [1, 1, 2], "run_position": ["init", "mid", "end"],
    ...                    "bow_join": ["", "bow change", "legato"]})
    >>> for tags in note_contexts([{"start": 0.0}, {"start": 0.5}, {"start": 0.61}], ev):
    ...     print(tags)
    ['attack']
    ['bow change', 'short note']
    ['legato', 'string crossing', 'double stop', 'dynamic change']
    """
    if not len(events):
        return [["other"] for _ in notes]
    out = []
    for k in matched_events(notes, events):
        e = events.iloc[k]
        prev = events.iloc[k - 1] if k > 0 else None
        tags = []
        if prev is None or str(e["run_position"]) in ("init", "iso"):
            tags.append("attack")
        else:
            if str(e.get("bow_join", "")) in CONTEXTS:
                tags.append(str(e["bow_join"]))
            if int(e["string"]) != int(prev["string"]):
                tags.append("string crossing")
        if float(e["played_end"]) - float(e["t0"]) < SHORT_S:
            tags.append("short note")
        if int(e["n_strings"]) >= 2:
            tags.append("double stop")
        if prev is not None and abs(float(e["dynamic"]) - float(prev["dynamic"])) >= DYNAMIC_STEP:
            tags.append("dynamic change")
        out.append(tags or ["other"])
    return out


def note_failures(note: Mapping[str, Any]) -> list[str]:
    """How one evaluated note fails (empty: it does not).

    Examples
    --------
    >>> note_failures({"attack_ms": 80.0, "helmholtz_share": 0.95, "sustained_hops": 20,
    ...                "sustained_class_histogram": {"1": 0, "2": 0, "3": 20, "4": 0, "5": 0}})
    ['slow attack']
    """
    out = []
    attack = float(note["attack_ms"])
    if note["sustained_hops"] > 0 and (not np.isfinite(attack) or attack > ATTACK_MS):
        out.append("slow attack")
    share = float(note["helmholtz_share"])
    if np.isfinite(share) and share < HELMHOLTZ:
        out.append("unsteady")
    hist = note["sustained_class_histogram"]
    total = sum(hist.values())
    if total and hist["5"] / total > CLASS5:
        out.append("class 5")
    return out


def why(notes: Sequence[Mapping[str, Any]], *, worst: int = 5) -> dict[str, Any]:
    """Counts of failing notes per failure and per context, and the worst examples.

    ``by_context`` counts the failing notes of each context, ``notes_by_context`` all the
    notes of each context (so a context's failure rate is their ratio).

    ``notes`` are evaluated notes carrying ``failures``, ``contexts``, ``excerpt``,
    ``seed``, ``part``, ``measure`` and ``pitch`` (as :mod:`pipelines.reports.compare`
    annotates them). Worst first: most failures, then lowest Helmholtz share, then slowest
    attack.
    """
    failing = [n for n in notes if n["failures"]]
    by_failure = Counter(f for n in failing for f in n["failures"])
    by_context = Counter(c for n in failing for c in n["contexts"])
    in_context = Counter(c for n in notes for c in n["contexts"])

    def badness(n):
        share = n["helmholtz_share"] if np.isfinite(n["helmholtz_share"]) else 1.0
        attack = n["attack_ms"] if np.isfinite(n["attack_ms"]) else 1e9
        return (-len(n["failures"]), share, -attack)

    keys = ("excerpt", "seed", "part", "measure", "pitch", "failures", "contexts",
            "helmholtz_share", "attack_ms")
    return {"notes": len(notes), "failing": len(failing),
            "by_failure": {f: by_failure.get(f, 0) for f in FAILURES},
            "by_context": {c: by_context.get(c, 0) for c in CONTEXTS},
            "notes_by_context": {c: in_context.get(c, 0) for c in CONTEXTS},
            "worst": [{**{k: n[k] for k in keys}, "database": n.get("database", 0)}
                      for n in sorted(failing, key=badness)[:worst]]}


def why_sentence(method: str, w: Mapping[str, Any]) -> str:
    """One line of the why for one method.

    Examples
    --------
    >>> w = {"notes": 10, "failing": 3, "by_failure": {"slow attack": 3, "unsteady": 1,
    ...      "class 5": 0}, "by_context": {"attack": 2, "string crossing": 1, "short note": 0,
    ...      "double stop": 0, "dynamic change": 0, "other": 0}, "notes_by_context":
    ...      {"attack": 4, "string crossing": 2}, "worst": [{"excerpt": "x",
    ...      "seed": 0, "part": "Violin I", "measure": 3, "pitch": "A4",
    ...      "failures": ["slow attack"], "contexts": ["attack"], "helmholtz_share": 0.5,
    ...      "attack_ms": 90.0}]}
    >>> import textwrap
    >>> print(textwrap.fill(why_sentence("rules", w), 80))
    rules: 3 of 10 notes fail (slow attack 3, unsteady 1); at attack 2 of 4, string
    crossing 1 of 2; worst: x m. 3 Violin I A4 (slow attack; attack).
    """
    if not w["failing"]:
        return f"{method}: none of {w['notes']} notes fails."
    how = ", ".join(f"{k} {v}" for k, v in w["by_failure"].items() if v)
    total = w.get("notes_by_context", {})
    where = ", ".join(f"{k} {v}" + (f" of {total[k]}" if k in total else "")
                      for k, v in sorted(w["by_context"].items(), key=lambda kv: -kv[1])
                      if v)
    ex = "; ".join(f"{n['excerpt']} m. {n['measure']} {n['part']} {n['pitch']} "
                   f"({', '.join(n['failures'])}; {', '.join(n['contexts'])})"
                   for n in w["worst"][:2])
    return (f"{method}: {w['failing']} of {w['notes']} notes fail ({how}); at {where}; "
            f"worst: {ex}.")


__all__ = ["ATTACK_MS", "CLASS5", "CONTEXTS", "FAILURES", "HELMHOLTZ", "SHORT_S",
           "matched_events", "note_contexts", "note_failures", "verdict_sentence", "why",
           "why_sentence"]
