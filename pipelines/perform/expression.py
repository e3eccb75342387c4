"""The left hand's expression: intonation (a pitch offset per note) and vibrato (a contour).

Both are pitch deviations in cents from the equal-tempered note and both reach the actions
table through the finger: a note ``semitones`` above the open string deviating by ``c``
cents is stopped at ``finger_ratio(semitones + c / 100)``, i.e.
``r = 1 - (1 - r0) 2**(-c/1200)`` (the stopped length ``L (1 - r)`` sounds ``f0 / (1 - r)``).

- :func:`intonation_cents`: one offset per note, drawn from N(0, sigma) where sigma combines
  the expressive spread (``[intonation] sigma``) and Vivi's skill error
  (``[skill] pitch_sigma``, semitones) as independent errors; plus the expressive
  intonation of semitone steps (a note leading a semitone up is played higher, one leading
  a semitone down lower). Open strings cannot be re-tuned and keep 0.
- :func:`assign_vibrato` / :func:`vibrato_cents`: a sine of ``rate`` (Hz) and peak
  ``extent`` (cents) that starts ``onset_delay`` after the note and fades in over
  ``fade_in`` (on a short note each at most ``onset_share`` of its length: the vibrato of
  a quick note starts sooner); rate and extent depend on the dynamic, the note's length,
  its place in the phrase, the performer (one draw per performance) and each note (one
  draw per note). Short notes get none; open strings none unless ``[vibrato] open_strings``.

Every draw comes from the ``rng`` the rules are given, so a seed fixes the performance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

_OPEN = 1e-6  # semitones: a string this close to open is played open
_MF = 5.0  # the dynamic level (0..9 scale) at which the configured rate and extent hold


@dataclass(frozen=True)
class Vibrato:
    """One note's vibrato.

    ``rate`` (Hz), peak ``extent`` (cents), ``phase`` (rad), the time it starts
    (``start``, s) and its fade-in (``fade``, s).
    """

    rate: float
    extent: float
    phase: float
    start: float
    fade: float


def vibrato_cents(vibrato: Vibrato | None, t: np.ndarray, *,
                  one_sided: bool = False) -> np.ndarray:
    """Pitch deviation (cents) of a vibrato at times ``t`` (s); zeros for ``None``.

    Parameters
    ----------
    vibrato : Vibrato or None
    t : np.ndarray [shape=(n,)], s
    one_sided : bool
        Deviate only upwards, between 0 and ``extent`` (an open string can only be
        shortened, by a finger touching it).

    Returns
    -------
    np.ndarray [shape=(n,)], cents
        ``extent * env(t) * sin(2 pi rate (t - start) + phase)`` with ``env`` rising
        linearly from 0 at ``start`` to 1 at ``start + fade``.

    Examples
    --------
    >>> v = Vibrato(rate=5.0, extent=10.0, phase=0.0, start=0.2, fade=0.0)
    >>> (vibrato_cents(v, np.array([0.1, 0.25])).round(6) + 0.0).tolist()
    [0.0, 10.0]
    """
    t = np.asarray(t, dtype=np.float64)
    if vibrato is None:
        return np.zeros(t.shape)
    since = t - vibrato.start
    env = np.clip(since / vibrato.fade, 0.0, 1.0) if vibrato.fade > 0 else \
        (since >= 0).astype(np.float64)
    wave = np.sin(2.0 * np.pi * vibrato.rate * since + vibrato.phase)
    if one_sided:
        wave = 0.5 * (wave + 1.0)
    return vibrato.extent * env * wave


def intonation_cents(midi: np.ndarray, onset: np.ndarray, stopped: np.ndarray,
                     config: dict[str, Any], skill: int,
                     rng: np.random.Generator) -> np.ndarray:
    """Pitch offset (cents) of each note: expressive intonation plus the skill's error.

    Parameters
    ----------
    midi : np.ndarray [shape=(n,)]
        MIDI pitches of one part's notes, sorted by onset.
    onset : np.ndarray [shape=(n,)], s
        Their onsets (the next note is the first with a later onset).
    stopped : np.ndarray [shape=(n,)], bool
        Notes played with a finger down (open strings get 0).
    config : dict
        Rules configuration (``[intonation]``, ``[skill] pitch_sigma``).
    skill : int
        Vivi skill level 0..3.
    rng : numpy.random.Generator

    Returns
    -------
    np.ndarray [shape=(n,)], cents

    Examples
    --------
    >>> from pipelines.perform.config import load_config
    >>> cfg = load_config()
    >>> cfg["intonation"]["sigma"] = 0.0
    >>> intonation_cents(np.array([71.0, 72.0, 71.0]), np.array([0.0, 1.0, 2.0]),
    ...                  np.ones(3, bool), cfg, 3, np.random.default_rng(0)).tolist()
    [4.0, -4.0, 0.0]
    """
    into = config["intonation"]
    midi = np.asarray(midi, dtype=np.float64)
    onset = np.asarray(onset, dtype=np.float64)
    stopped = np.asarray(stopped, dtype=bool)
    sigma = float(np.hypot(into["sigma"], 100.0 * config["skill"]["pitch_sigma"][skill]))
    cents = np.zeros(midi.size)
    if sigma > 0 and stopped.any():
        cents[stopped] = rng.normal(0.0, sigma, int(stopped.sum()))
    nxt = np.searchsorted(onset, onset, side="right")
    has = nxt < midi.size
    step = np.zeros(midi.size)
    step[has] = midi[nxt[has]] - midi[has]
    cents += into["semitone_step"] * (np.isclose(step, 1.0).astype(float)
                                      - np.isclose(step, -1.0).astype(float))
    return np.where(stopped, cents, 0.0)


def assign_vibrato(events: list, config: dict[str, Any], rng: np.random.Generator) -> None:
    """Give each long enough bowed event its :class:`Vibrato` (``event.vibrato``).

    Parameters
    ----------
    events : list of pipelines.perform.events.Event
        Articulated events (``played_end`` set), in time order.
    config : dict
        Rules configuration (``[vibrato]``).
    rng : numpy.random.Generator
        One performer draw (rate, extent), then per note: rate, extent, phase.
    """
    vib = config["vibrato"]
    if not vib["enabled"] or vib["extent"] <= 0:
        return
    performer_rate = vib["rate"] + rng.normal(0.0, vib["performer_rate_sigma"])
    performer_extent = vib["extent"] * float(np.exp(rng.normal(0.0,
                                                               vib["performer_extent_sigma"])))
    for e in events:
        draws = rng.normal(0.0, 1.0, 2)  # drawn for every event: the stream is stable
        phase = float(rng.uniform(0.0, 2.0 * np.pi))
        length = e.played_end - e.t0
        open_string = all(s <= _OPEN for s in e.semitones)
        if e.pizz or length < vib["min_duration"] or (open_string and not vib["open_strings"]):
            continue
        level = (e.dynamic - _MF) / 4.0  # -1 at p (ish) .. +1 at ff (ish)
        long = float(np.clip((length - 0.5) / 1.5, 0.0, 1.0))
        phrase_end = e.rest_after or e.run_position in ("end", "iso")
        extent = performer_extent * (1.0 + vib["dynamic_extent"] * level) \
            * (1.0 + vib["length_extent"] * long) \
            * (vib["phrase_end_extent"] if phrase_end else 1.0) \
            * float(np.exp(vib["extent_sigma"] * draws[1]))
        rate = performer_rate + vib["dynamic_rate"] * level + vib["rate_sigma"] * draws[0]
        e.vibrato = Vibrato(rate=float(np.clip(rate, 3.0, 9.0)), extent=max(float(extent), 0.0),
                            phase=phase,
                            start=e.t0 + min(vib["onset_delay"], vib["onset_share"] * length),
                            fade=min(vib["fade_in"], vib["onset_share"] * length))


def string_cents(e: Any, semitones: float, t: np.ndarray, config: dict[str, Any]) -> np.ndarray:
    """Vibrato (cents) of one string of event ``e`` at ``t`` (s).

    None on an open string unless ``[vibrato] open_strings`` (then one-sided).
    """
    vibrato = getattr(e, "vibrato", None)
    if semitones <= _OPEN:
        if not config["vibrato"]["open_strings"]:
            return np.zeros(np.shape(t))
        return vibrato_cents(vibrato, t, one_sided=True)
    return vibrato_cents(vibrato, t)
