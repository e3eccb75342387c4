"""How fast a string in Helmholtz motion takes the next note: a bow change or a finger change.

Most notes of real music start from the note before, not from silence: at a *bow change*
(the bow slows to a stop on the string and turns) or, under a slur, at a *finger change*
with the bow moving. Both are measured on the public block API of
:class:`synth.instrument.Instrument` (no body), after the same set-up: the bow is set on
the string at the string's reference force (a start that speaks), accelerates at
:data:`SETUP_ACCELERATION` to ``bow_velocity`` and the force glides (exponentially) to the
note's ``bow_force`` between :data:`SETUP_BITE` and :data:`SETUP_BITE` +
:data:`SETUP_GLIDE`; Helmholtz motion is checked over the last :data:`CHECKED` s before
the change (:attr:`NoteChange.helmholtz_before`).

- :func:`bow_change`: the bow decelerates at ``acceleration`` through zero and accelerates
  at the same rate back to ``bow_velocity`` in the other direction, beta held and the force
  held or eased into the turn (``ease``, as the rules lighten a stroke's last note);
- :func:`finger_change`: a finger stops the string ``semitones`` higher at one block's
  boundary, the bow held.

The attack is the time from the change (the reversal, or the finger's landing) to the first
of :data:`ATTACK_PERIODS` consecutive slip intervals within
:data:`synth.playability.PERIOD_TOLERANCE` of the new period (the yardstick's rule,
:mod:`pipelines.listening.regularity`); None when not reached within :data:`LIMIT`.

Examples
--------
>>> c = finger_change("violin", 1, bow_force=1.0, semitones=2.0)
>>> c.helmholtz_before, c.attack is not None and c.attack < 0.05
(True, True)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from data_schemas.errors import ParameterError
from data_schemas.instruments import finger_ratio
from synth.controls import BowControl
from synth.instrument import Instrument
from synth.playability import PERIOD_TOLERANCE
from synth.strings import InstrumentConstants

#: Output samples per block (the controls ramp linearly within a block).
HOP = 64
#: Set-up: bow acceleration (m/s^2), time at the reference force (s), glide to the note's
#: force (s), time of the change (s from the bow's start).
SETUP_ACCELERATION, SETUP_BITE, SETUP_GLIDE, CHANGE_AT = 2.0, 0.2, 0.3, 0.8
#: Span before the change over which Helmholtz motion is checked, s.
CHECKED = 0.2
#: Consecutive regular periods that end an attack.
ATTACK_PERIODS = 5
#: Longest attack measured, s from the change.
LIMIT = 0.4


@dataclass(frozen=True)
class NoteChange:
    """One measured change.

    Attributes
    ----------
    helmholtz_before : bool
        At least 90 % of the slip intervals in the :data:`CHECKED` s before the change are
        one period (within 3 %): the set-up reached Helmholtz motion.
    attack : float or None, s
        From the change to the first of :data:`ATTACK_PERIODS` regular periods.
    """

    helmholtz_before: bool
    attack: float | None


def _setup(bite: float, bow_force: float, bow_velocity: float,
           t: float) -> tuple[float, float]:
    """Bow speed (m/s, unsigned) and force (N) of the set-up at time ``t`` (s)."""
    x = min(max(t - SETUP_BITE, 0.0) / SETUP_GLIDE, 1.0)
    return min(SETUP_ACCELERATION * t, bow_velocity), bite * (bow_force / bite) ** x


def reversal_speed(t: float, bow_velocity: float, acceleration: float) -> float:
    """Signed bow speed (m/s) of a bow change at time ``t`` (s from the start of slowing).

    Examples
    --------
    >>> [round(reversal_speed(t, 0.3, 10.0), 3) for t in (0.0, 0.02, 0.03, 0.05, 0.1)]
    [0.3, 0.1, 0.0, -0.2, -0.3]
    """
    return float(np.clip(bow_velocity - acceleration * t, -bow_velocity, bow_velocity))


def slip_onsets(instrument: str | InstrumentConstants, string: int, seed: int, duration: float,
                control: Callable[[Instrument, float], BowControl]
                ) -> tuple[np.ndarray, float]:
    """Bow one string of a fresh instrument (no body) by ``control``; its slip onsets.

    Parameters
    ----------
    instrument : str or InstrumentConstants
    string : int
        String index, 0 = lowest.
    seed : int
        Seed of the instrument (its friction noise).
    duration : float, s
    control : callable
        ``control(instrument, t)`` -> :class:`synth.controls.BowControl` at the end of each
        block of :data:`HOP` samples ending at ``t`` s.

    Returns
    -------
    onsets : np.ndarray [shape=(k,)], s
        Slip onsets of the string (the instrument's contact diagnostics).
    f0 : float, Hz
        The open string's nominal frequency.

    Examples
    --------
    >>> onsets, f0 = slip_onsets("violin", 1, 0, 0.5, lambda inst, t: BowControl(
    ...     min(5.0 * t, 0.3), 1.5, 0.1))
    >>> round(f0, 1), bool(abs(np.sum(onsets > 0.3) / (0.2 * f0) - 1.0) < 0.05)
    (293.7, True)
    """
    inst = Instrument(instrument, seed=seed, body=None)
    rate = inst.sample_rate
    onsets = []
    for k in range(int(np.ceil(duration * rate / HOP))):
        block = inst.process(HOP, {string: control(inst, (k + 1) * HOP / rate)})
        onsets.append(block.diagnostics[string].onset_times)
    f0 = inst.voices[string].string.nominal_frequency(inst.constants.tuning_a4)
    return np.concatenate(onsets), float(f0)


def measure_change(onsets: np.ndarray, before: float, after: float, change: float,
                   attack_from: float | None = None) -> NoteChange:
    """Helmholtz motion before ``change``, and the attack from ``attack_from``.

    Parameters
    ----------
    onsets : np.ndarray [shape=(k,)], s
        Slip onsets of the string, increasing (:func:`slip_onsets`).
    before, after : float, Hz
        Nominal frequencies before and after the change.
    change : float, s
        Time of the change; Helmholtz motion is checked over the :data:`CHECKED` s before.
    attack_from : float, optional, s
        Where the attack is timed from (default ``change``).

    Returns
    -------
    NoteChange
        The attack runs to the first of :data:`ATTACK_PERIODS` regular periods within
        :data:`LIMIT` s (None when there is none).

    Examples
    --------
    >>> onsets = np.r_[np.arange(0.6, 0.8, 0.004), 0.8 + 0.01 + np.arange(30) * 0.004]
    >>> c = measure_change(onsets, 250.0, 250.0, 0.8)
    >>> c.helmholtz_before, round(c.attack, 4)
    (True, 0.01)
    """
    pre = onsets[(onsets >= change - CHECKED) & (onsets < change)]
    ok = np.abs(np.diff(pre) * before - 1.0) < PERIOD_TOLERANCE
    helm = bool(ok.size > 2 and ok.mean() >= 0.9)
    start = change if attack_from is None else attack_from
    post = onsets[(onsets >= start) & (onsets < start + LIMIT)]
    good = np.abs(np.diff(post) * after - 1.0) < PERIOD_TOLERANCE
    if good.size < ATTACK_PERIODS:
        return NoteChange(helm, None)
    runs = np.convolve(good.astype(np.int64), np.ones(ATTACK_PERIODS, np.int64), "valid")
    hits = np.flatnonzero(runs == ATTACK_PERIODS)
    return NoteChange(helm, float(post[hits[0]] - start) if hits.size else None)


def check_bowing(bow_force: float, bow_velocity: float, beta: float) -> None:
    """Refuse a bowing that cannot be played: ParameterError naming the three values.

    Examples
    --------
    >>> check_bowing(1.0, 0.3, 0.1)
    """
    if not (bow_force > 0.0 and bow_velocity > 0.0 and 0.0 < beta < 0.5):
        raise ParameterError(f"need bow_force > 0 N, bow_velocity > 0 m/s and 0 < beta < 0.5;"
                             f" got {bow_force}, {bow_velocity}, {beta}")


def eased_force(t: float, turn: float, bow_force: float, ease: float = 1.0,
                ease_time: float = 0.1) -> float:
    """Bow force (N) at time ``t`` (s) of a bow eased into its turn at ``turn`` (s).

    Linearly from ``bow_force`` to ``ease * bow_force`` over the ``ease_time`` s before the
    turn, as the rules lighten the last note of a stroke (``[articulations]
    lighten_force``, ``lighten_time``); ``bow_force`` again from the turn on.

    Examples
    --------
    >>> [round(eased_force(t, 1.0, 2.0, 0.5, 0.1), 3) for t in (0.8, 0.95, 1.0, 1.01)]
    [2.0, 1.5, 1.0, 2.0]
    """
    if t > turn:
        return bow_force
    tail = min(max((t - (turn - ease_time)) / ease_time, 0.0), 1.0)
    return bow_force * (1.0 - (1.0 - ease) * tail)


def bow_change(instrument: str | InstrumentConstants, string: int, *, bow_force: float,
               acceleration: float, bow_velocity: float = 0.3, beta: float = 0.1,
               seed: int = 0, ease: float = 1.0, ease_time: float = 0.1) -> NoteChange:
    """Turn the bow on a string in Helmholtz motion; how long until it is back.

    Parameters
    ----------
    instrument : str or InstrumentConstants
    string : int
        String index, 0 = lowest.
    bow_force : float, N
        Held through the change (but see ``ease``).
    acceleration : float, m/s^2
        Of the slowing down and of the new stroke's start (the bow turns at
        ``CHANGE_AT + bow_velocity / acceleration`` s).
    bow_velocity : float, m/s
        Speed before and after the change.
    beta : float
    seed : int
    ease, ease_time : float (share in (0, 1]) and float (s, > 0)
        The force eases to ``ease`` times ``bow_force`` over the ``ease_time`` s before the
        turn (:func:`eased_force`); 1 holds it.

    Returns
    -------
    NoteChange
        Its attack timed from the reversal.

    Examples
    --------
    >>> c = bow_change("violin", 1, bow_force=2.0, acceleration=20.0)
    >>> c.helmholtz_before, c.attack is None or c.attack > 0.005
    (True, True)
    """
    check_bowing(bow_force, bow_velocity, beta)
    if not acceleration > 0.0:
        raise ParameterError(f"acceleration={acceleration} m/s^2 must be > 0")
    if not (0.0 < ease <= 1.0 and ease_time > 0.0):
        raise ParameterError(f"need 0 < ease <= 1 and ease_time > 0 s; got {ease}, {ease_time}")
    turn = CHANGE_AT + bow_velocity / acceleration

    def control(inst: Instrument, t: float) -> BowControl:
        if t <= CHANGE_AT:
            bite = inst.voices[string].string.reference_force
            return BowControl(*_setup(bite, bow_force, bow_velocity, t), beta)
        return BowControl(reversal_speed(t - CHANGE_AT, bow_velocity, acceleration),
                          eased_force(t, turn, bow_force, ease, ease_time), beta)

    onsets, f0 = slip_onsets(instrument, string, seed, turn + LIMIT, control)
    return measure_change(onsets, f0, f0, CHANGE_AT, turn)


def finger_change(instrument: str | InstrumentConstants, string: int, *, bow_force: float,
                  semitones: float, bow_velocity: float = 0.3, beta: float = 0.1,
                  seed: int = 0) -> NoteChange:
    """Stop a string in Helmholtz motion higher, bow held; how long until it is back.

    Parameters
    ----------
    instrument : str or InstrumentConstants
    string : int
    bow_force : float, N
    semitones : float
        Above the open string (the set-up bows the open string).
    bow_velocity : float, m/s
    beta : float
        Of the effective length, before and after.
    seed : int

    Returns
    -------
    NoteChange
        Its attack timed from :data:`CHANGE_AT` (the finger lands within the block that
        ends after it: its ratio ramps over that block).
    """
    check_bowing(bow_force, bow_velocity, beta)
    ratio = float(finger_ratio(semitones))

    def control(inst: Instrument, t: float) -> BowControl:
        bite = inst.voices[string].string.reference_force
        speed, force = _setup(bite, bow_force, bow_velocity, t)
        return BowControl(speed, force, beta, ratio if t > CHANGE_AT else 0.0)

    onsets, f0 = slip_onsets(instrument, string, seed, CHANGE_AT + LIMIT, control)
    return measure_change(onsets, f0, f0 / (1.0 - ratio), CHANGE_AT)


__all__ = ["NoteChange", "bow_change", "check_bowing", "finger_change", "measure_change",
           "reversal_speed", "slip_onsets"]
