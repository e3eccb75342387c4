"""From the comparison's renders to its results: intervals, winners, verdict and why.

:func:`summarise` turns the finished jobs of :func:`pipelines.reports.compare.compare`
into the content of ``results.json``:

- ``verdict``: one sentence (:func:`pipelines.reports.verdict.verdict_sentence`);
- ``why``: per method, failing notes by failure and context with the worst examples, and
  ``why_text``, one line per method;
- ``summary``: method -> figure -> ``{mean, low, high}`` over all excerpts and seeds,
  ``winners``: figure -> method or null (no separation), ``contenders``: figure -> the
  methods not separated from the best;
- ``excerpts``: the same per excerpt;
- ``instruments``: the same per instrument (its parts' notes pooled over the excerpts),
  in order of first appearance, each with its own verdict;
- ``timing``: method -> mean render seconds and real-time factor (reported, not scored);
- ``runs``: method -> excerpt -> run -> the yardstick's figures (or ``error``); a run is
  its seed on the first gesture database, ``"S@dbK"`` for seed S on database K (counted
  from 0 in ``setup["databases"]``);
- ``failed``: method -> its first error, for a method that failed on every excerpt (it is
  not compared); ``left_out``: excerpt -> which methods failed on it and why (such an
  excerpt is left out of the pooled figures of every method, so that all are compared on
  the same music; its own table holds the methods that played it);
- ``setup``: excerpts, seeds, methods, gesture databases and how the intervals were
  computed;
- ``media``: method -> excerpt -> audio and bowing plot of the first seed.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pipelines.reports import intervals as iv
from pipelines.reports.figures import FIGURES
from pipelines.reports.verdict import verdict_sentence, why, why_sentence

INTERVAL_TEXT = (f"{iv.LEVEL:.0%} percentile interval of a two-stage bootstrap "
                 f"({iv.N_BOOT} replicates, seed {iv.BOOTSTRAP_SEED}): seeds drawn with "
                 "replacement, then each drawn seed's notes with replacement; mean = mean "
                 "over seeds of each seed's figure over all excerpts")
DATABASES_TEXT = ("; with several gesture databases each sampling seed on each database is "
                  "one unit of the draw, so the sampling intervals hold the databases' "
                  "spread too")


def run_label(seed: int, draw: int = 0) -> str:
    """The key of one run in ``runs``: its seed, with its database beyond the first.

    Examples
    --------
    >>> run_label(3), run_label(3, 2)
    ('3', '3@db2')
    """
    return str(seed) if draw == 0 else f"{seed}@db{draw}"


def split_run_label(label: str) -> tuple[int, int]:
    """The seed and database index of a :func:`run_label`.

    Examples
    --------
    >>> split_run_label("3"), split_run_label("3@db2")
    ((3, 0), (3, 2))
    """
    seed, _, draw = label.partition("@db")
    return int(seed), int(draw or 0)


def _units(done: list[dict], method: str, seeds: list[int]) -> list[tuple[int, int]]:
    """The bootstrap's units of a method: each seed on each database it was played on."""
    draws = sorted({r.get("draw", 0) for r in done if r["method"] == method}) or [0]
    return [(s, d) for s in seeds for d in draws]


def _intervals(done: list[dict], methods: list[str], seeds: list[int],
               excerpt: str | None = None,
               instrument: str | None = None) -> dict[str, dict[str, iv.Interval]]:
    """Intervals (figure -> method) over one excerpt's or instrument's notes (or all)."""
    out: dict[str, dict[str, iv.Interval]] = {f: {} for f in FIGURES}
    for m in methods:
        per_seed = []
        for s, d in _units(done, m, seeds):
            notes = [n for r in done if r["method"] == m and r["seed"] == s
                     and r.get("draw", 0) == d
                     and (excerpt is None or r["excerpt"] == excerpt) for n in r["notes"]
                     if instrument is None or n.get("instrument") == instrument]
            per_seed.append(iv.note_arrays(notes))
        if not any(a["sustained_hops"].size for a in per_seed):
            continue
        for fig, interval in iv.bootstrap(per_seed).items():
            out[fig][m] = interval
    return out


def _table(ivs: dict[str, dict[str, iv.Interval]]) -> dict[str, Any]:
    """The JSON form: per-method intervals, winners and contenders of each figure."""
    methods = list(dict.fromkeys(m for per in ivs.values() for m in per))
    return {
        "summary": {m: {f: ivs[f][m].as_dict() for f in FIGURES if m in ivs[f]}
                    for m in methods},
        "winners": {f: iv.winner(ivs[f], FIGURES[f]) for f in FIGURES},
        "contenders": {f: iv.contenders(ivs[f], FIGURES[f]) for f in FIGURES},
    }


def _timing(done: list[dict], methods: list[str]) -> dict[str, dict[str, float]]:
    out = {}
    for m in methods:
        runs = [r["figures"] for r in done if r["method"] == m and "error" not in r["figures"]]
        if runs:
            out[m] = {k: float(np.mean([f[k] for f in runs]))
                      for k in ("render_seconds", "real_time_factor", "audio_seconds")}
    return out


def _per_instrument(good: list[dict], methods: list[str], seeds: list[int],
                    n_excerpts: int, n_databases: int) -> dict[str, dict[str, Any]]:
    """Per instrument, in order of first appearance: its verdict and its table."""
    out = {}
    for i in dict.fromkeys(n["instrument"] for r in good for n in r["notes"]
                           if n.get("instrument")):
        ivs = _intervals(good, methods, seeds, instrument=i)
        out[i] = {"verdict": verdict_sentence(ivs, n_excerpts=n_excerpts, n_seeds=len(seeds),
                                              instrument=i, n_databases=n_databases),
                  **_table(ivs)}
    return out


def _runs_and_media(done: list[dict], methods: list[str]) -> tuple[dict, dict]:
    """The runs (method -> excerpt -> run label -> figures) and the first seed's media."""
    runs: dict[str, dict[str, dict[str, Any]]] = {m: {} for m in methods}
    media: dict[str, dict[str, Any]] = {m: {} for m in methods}
    for r in done:
        label = run_label(r["seed"], r.get("draw", 0))
        runs[r["method"]].setdefault(r["excerpt"], {})[label] = r["figures"]
        if r["media"]:
            media[r["method"]][r["excerpt"]] = r["media"]
    return runs, media


def _failures(done: list[dict], methods: list[str], names: list[str]):
    """(method, excerpt) -> error; methods failing everywhere; excerpts left out."""
    errors = {(r["method"], r["excerpt"]): r["figures"]["error"] for r in done
              if "error" in r["figures"]}
    failed = {m: next(msg for (k, _), msg in errors.items() if k == m) for m in methods
              if all((m, e) in errors for e in names)}
    ok = [m for m in methods if m not in failed]
    left_out = {e: "; ".join(f"{m}: {errors[(m, e)]}" for m in ok if (m, e) in errors)
                for e in names if any((m, e) in errors for m in ok)}
    return errors, failed, left_out


def _verdict(pooled, n_excerpts: int, n_seeds: int, n_databases: int,
             left_out: dict[str, str], failed: dict[str, str]) -> str:
    """The verdict sentence, with what was left out in brackets."""
    verdict = verdict_sentence(pooled, n_excerpts=n_excerpts, n_seeds=n_seeds,
                               n_databases=n_databases)
    notes = [f"{e} left out, {msg}" for e, msg in left_out.items()]
    notes += [f"{m} not compared: {msg}" for m, msg in failed.items()]
    return verdict[:-1] + f" ({'; '.join(notes)})." if notes else verdict


def summarise(done: list[dict[str, Any]], *, excerpts: Sequence[dict[str, Any]],
              methods: list[str], seeds: list[int], title: str | None = None,
              databases: Sequence[str] = ()) -> dict[str, Any]:
    """The comparison's results (see the module doc) from its finished jobs.

    Parameters
    ----------
    done : list of dict
        :func:`pipelines.reports.compare.run_job` results: ``excerpt``, ``method``,
        ``seed``, ``draw`` (index in ``databases``; 0 when absent), ``figures`` (or
        ``{"error": ...}``), ``notes`` (annotated), ``media``.
    excerpts : sequence of dict
        What was played (``name``, ``path``, measures, parts).
    methods : list of str
    seeds : list of int
    title : str, optional
    databases : sequence of str
        The gesture databases the sampling methods played (recorded in ``setup``; with
        several, each seed on each database is one unit of the bootstrap).

    Returns
    -------
    dict

    Examples
    --------
    >>> hist = {"1": 0, "2": 0, "3": 9, "4": 1, "5": 0}
    >>> def job(method, seed, share):
    ...     note = {"sustained_hops": 10, "helmholtz_share": share, "reached_helmholtz": True,
    ...             "attack_ms": 30.0, "pitch_error_cents_median": 0.0,
    ...             "level_error_db_median": 0.0, "sustained_class_histogram": hist,
    ...             "failures": [], "contexts": ["attack"]}
    ...     return {"excerpt": "x", "method": method, "seed": seed, "media": None,
    ...             "figures": {"render_seconds": 1.0, "real_time_factor": 2.0,
    ...                         "audio_seconds": 2.0}, "notes": [note] * 4}
    >>> done = [job("a", s, 1.0) for s in (0, 1)] + [job("b", s, 0.5) for s in (0, 1)]
    >>> r = summarise(done, excerpts=[{"name": "x"}], methods=["a", "b"], seeds=[0, 1])
    >>> for clause in r["verdict"].split("; "):
    ...     print(clause)
    On 1 excerpt x 2 seeds, a beats b on Helmholtz share
    a and b do not separate on attack p90, class-3 share and class-5 share.
    >>> r["winners"]["helmholtz_share"], r["summary"]["b"]["helmholtz_share"]["mean"]
    ('a', 0.5)
    """
    names = [e["name"] for e in excerpts]
    errors, failed, left_out = _failures(done, methods, names)
    ok = [m for m in methods if m not in failed]
    good = [r for r in done if r["method"] in ok and r["excerpt"] not in left_out]
    pooled = _intervals(good, ok, seeds)
    whys = {m: why([n for r in good if r["method"] == m for n in r["notes"]]) for m in ok}
    per_excerpt = {}
    for e in names:
        played = [m for m in ok if (m, e) not in errors]
        per_excerpt[e] = _table(_intervals([r for r in done if r["method"] in played],
                                           played, seeds, e))
    n_db = len(databases)
    per_instrument = _per_instrument(good, ok, seeds, len(names) - len(left_out), n_db)
    runs, media = _runs_and_media(done, methods)
    verdict = _verdict(pooled, len(names) - len(left_out), len(seeds), n_db, left_out,
                       failed)
    return {
        "title": title or ", ".join(names),
        "verdict": verdict,
        "why": whys,
        "why_text": [why_sentence(m, w) for m, w in whys.items()],
        **_table(pooled),
        "excerpts": per_excerpt,
        "instruments": per_instrument,
        "timing": _timing(done, methods),
        "runs": runs,
        "failed": failed,
        "left_out": left_out,
        "setup": {"excerpts": list(excerpts), "seeds": seeds, "methods": methods,
                  "databases": list(databases),
                  "interval": INTERVAL_TEXT + (DATABASES_TEXT if n_db > 1 else ""),
                  "level": iv.LEVEL, "n_boot": iv.N_BOOT,
                  "bootstrap_seed": iv.BOOTSTRAP_SEED},
        "media": media,
    }


__all__ = ["DATABASES_TEXT", "INTERVAL_TEXT", "run_label", "split_run_label", "summarise"]
