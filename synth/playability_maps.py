"""Playability maps of the instrument model: Schelleng windows and Guettler attack maps.

Two measurements, both on the public block API of :class:`synth.instrument.Instrument`
(see ``shared/reference/sound-quality.md``):

- a **Schelleng window**: steady strokes (:func:`synth.playability.steady_stroke`, no body)
  over a grid of bow forces at one bow velocity and beta; the regime of each force as one
  letter (:data:`REGIME_LETTERS`), the lowest and highest Helmholtz force and the holes
  between them; compared with the violin bowing-machine lines
  F_min = k / beta^2 and F_max = c v / beta;
- a **Guettler attack**: the bow starts from rest at constant acceleration with constant
  force; the time from the first slip until Helmholtz motion (:func:`time_to_helmholtz`).

Examples
--------
>>> window_limits([0.1, 0.2, 0.4, 0.8], "mHxH")
(0.2, 0.8, 1)
>>> round(float(machine_f_min(0.1)), 4), round(float(machine_f_max(0.3, 0.1)), 3)
(0.0385, 2.595)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from data_schemas.instruments import instrument_facts, limits
from synth.controls import BowControl
from synth.instrument import Instrument
from synth.playability import StrokeReport, steady_stroke

#: Regime letters of a steady stroke: Helmholtz, multiple slipping (> 1.1 slips per
#: period, whatever the force), silent (no counted slip), anything else.
REGIME_LETTERS = {"H": "Helmholtz", "m": "multiple slipping (> 1.1 slips/period)",
                  ".": "silent (no slips)", "x": "other (aperiodic, < 1 slip/period)"}
#: Bowing-machine fit F_min = k / beta^2 (violin): k = 3.5e-4..4.2e-4 N; the middle is used.
MACHINE_K_RANGE = (3.5e-4, 4.2e-4)
MACHINE_K = 0.5 * sum(MACHINE_K_RANGE)
#: Bowing-machine fit F_max = c v / beta (violin): c = 0.73..1.0 kg/s; the middle is used.
MACHINE_C_RANGE = (0.73, 1.0)
MACHINE_C = 0.5 * sum(MACHINE_C_RANGE)
#: A measured limit passes when within this factor of the bowing-machine line.
CELL_FACTOR = 2.0
#: The issue's cells: violin G and D strings x these velocities (m/s) x these betas.
CELL_STRINGS = (("violin", 0), ("violin", 1))
CELL_VELOCITIES = (0.1, 0.3)
CELL_BETAS = (0.05, 0.08, 0.12, 0.18)
#: Player forces (N) per instrument, each expected to give Helmholtz motion on every string
#: at :data:`PLAYER_BETA` and :data:`PLAYER_VELOCITY`.
PLAYER_FORCES = {"violin": (0.15, 2.0), "viola": (0.2, 2.5), "cello": (0.5, 5.0)}
PLAYER_BETA = 0.1
PLAYER_VELOCITY = 0.3
#: Output samples per block of an attack (the velocity ramps linearly within a block).
HOP = 256
#: An attack has reached Helmholtz motion at the first onset followed by this many
#: consecutive slip-onset intervals within :data:`ATTACK_TOLERANCE` of the nominal period.
ATTACK_PERIODS = 5
ATTACK_TOLERANCE = 0.10
#: Longest attack measured, s from the first slip (longer: not reached).
ATTACK_LIMIT = 0.5
#: Longest wait for a first slip, s from the bow's start.
FIRST_SLIP_LIMIT = 1.0
#: Guettler's judgements of attack durations, s: perfect, creaky, loose.
PERFECT_ATTACK, CREAKY_ATTACK, LOOSE_ATTACK = 0.005, 0.050, 0.090


def regime_letter(report: StrokeReport) -> str:
    """One letter of :data:`REGIME_LETTERS` for a steady stroke."""
    if report.is_helmholtz:
        return "H"
    if report.slips_per_period > 1.1:
        return "m"
    if report.slips_per_period == 0.0:
        return "."
    return "x"


def force_grid(n: int, low: float = 0.005, high: float = 20.0) -> np.ndarray:
    """``n`` bow forces (N) log-spaced from ``low`` to ``high``."""
    return np.geomspace(low, high, int(n))


def window_limits(forces: Sequence[float], regimes: str,
                  ) -> tuple[float | None, float | None, int]:
    """Lowest and highest Helmholtz force and the non-Helmholtz forces between them.

    Parameters
    ----------
    forces : sequence of float, N
        Increasing bow forces.
    regimes : str
        One :data:`REGIME_LETTERS` letter per force.

    Returns
    -------
    f_min, f_max : float or None, N
        None when no force gives Helmholtz motion.
    holes : int
        Forces inside [f_min, f_max] without Helmholtz motion.
    """
    if len(forces) != len(regimes):
        raise ValueError(f"{len(forces)} forces but {len(regimes)} regime letters")
    inside = [i for i, r in enumerate(regimes) if r == "H"]
    if not inside:
        return None, None, 0
    lo, hi = inside[0], inside[-1]
    return float(forces[lo]), float(forces[hi]), (hi - lo + 1) - len(inside)


@dataclass(frozen=True)
class Window:
    """Schelleng window of one string at one bow velocity and beta.

    Attributes
    ----------
    instrument : str
    string : int
        0 = lowest.
    bow_velocity : float, m/s
    beta : float
    forces : tuple of float, N
    regimes : str
        One :data:`REGIME_LETTERS` letter per force.
    pitch_cents : tuple of float, cents
        Sounding pitch against the nominal one per force (NaN where not in Helmholtz
        motion): how the pitch moves with bow force.
    """

    instrument: str
    string: int
    bow_velocity: float
    beta: float
    forces: tuple[float, ...]
    regimes: str
    pitch_cents: tuple[float, ...] = ()

    @property
    def limits(self) -> tuple[float | None, float | None, int]:
        """``(f_min, f_max, holes)`` of :func:`window_limits`."""
        return window_limits(self.forces, self.regimes)

    def as_dict(self) -> dict:
        """JSON-ready summary (forces are given once, elsewhere)."""
        f_min, f_max, holes = self.limits
        return {"instrument": self.instrument, "string": self.string,
                "string_name": instrument_facts(self.instrument).string_names[self.string],
                "bow_velocity": self.bow_velocity, "beta": self.beta, "f_min": f_min,
                "f_max": f_max, "holes": holes, "regimes": self.regimes,
                "pitch_cents": [None if not math.isfinite(c) else round(c, 2)
                                for c in self.pitch_cents]}


def measure_window(instrument: str, string: int, bow_velocity: float, beta: float,
                   forces: Sequence[float], *, seed: int = 0) -> Window:
    """Steady strokes (no body) at each force; see :class:`Window`."""
    reports = [steady_stroke(instrument, string, bow_force=float(f), bow_velocity=bow_velocity,
                             beta=beta, seed=seed, body=None) for f in forces]
    letters = "".join(regime_letter(r) for r in reports)
    pitch = tuple(float(r.pitch_error_cents) if r.is_helmholtz else math.nan for r in reports)
    return Window(instrument, string, float(bow_velocity), float(beta),
                  tuple(float(f) for f in forces), letters, pitch)


def machine_f_min(beta: float | np.ndarray, k: float = MACHINE_K) -> float | np.ndarray:
    """Bowing-machine lower force limit k / beta^2, N."""
    return k / np.square(beta)


def machine_f_max(bow_velocity: float, beta: float | np.ndarray,
                  c: float = MACHINE_C) -> float | np.ndarray:
    """Bowing-machine upper force limit c v / beta, N."""
    return c * bow_velocity / np.asarray(beta, dtype=float)


def cell_check(measured: float | None, line: float, factor: float = CELL_FACTOR,
               ) -> tuple[float | None, bool]:
    """Ratio measured / line and whether it lies within ``factor`` either way.

    A missing measurement (no Helmholtz force) fails with ratio None. The comparison
    allows a relative rounding of 1e-9, so a limit at exactly ``factor`` times passes.
    """
    if measured is None:
        return None, False
    ratio = float(measured) / float(line)
    slack = 1.0 + 1e-9
    return ratio, 1.0 / (factor * slack) <= ratio <= factor * slack


def schelleng_cells(windows: Sequence[Window]) -> list[dict]:
    """The issue's cells (:data:`CELL_STRINGS` x velocities x betas x {F_min, F_max}).

    Cells whose window was not measured are left out (a quick run has fewer).
    """
    by_key = {(w.instrument, w.string, w.bow_velocity, w.beta): w for w in windows}
    cells = []
    for name, s in CELL_STRINGS:
        for v in CELL_VELOCITIES:
            for beta in CELL_BETAS:
                window = by_key.get((name, s, v, beta))
                if window is None:
                    continue
                f_min, f_max, _ = window.limits
                for limit, measured, line in (("F_min", f_min, machine_f_min(beta)),
                                              ("F_max", f_max, machine_f_max(v, beta))):
                    ratio, passed = cell_check(measured, float(line))
                    cells.append({"instrument": name, "string": s, "bow_velocity": v,
                                  "beta": beta, "limit": limit, "measured": measured,
                                  "line": float(line), "ratio": ratio, "pass": passed})
    return cells


def player_cases() -> list[tuple[str, int, float]]:
    """``(instrument, string, force)`` of the player-force check (3 x 4 x 2 = 24)."""
    return [(name, s, force) for name, forces in PLAYER_FORCES.items()
            for s in range(instrument_facts(name).n_strings) for force in forces]


def player_case(instrument: str, string: int, force: float, *, seed: int = 0) -> dict:
    """One steady stroke of the player-force check, as a JSON-ready dict."""
    report = steady_stroke(instrument, string, bow_force=force, bow_velocity=PLAYER_VELOCITY,
                           beta=PLAYER_BETA, seed=seed, body=None)
    return {"instrument": instrument, "string": string, "bow_force": force,
            "regime": regime_letter(report), "helmholtz": bool(report.is_helmholtz),
            "slips_per_period": round(float(report.slips_per_period), 3),
            "helmholtz_share": round(float(report.helmholtz_share), 3)}


def time_to_helmholtz(onset_times: np.ndarray, frequency: float, *,
                      periods: int = ATTACK_PERIODS, tolerance: float = ATTACK_TOLERANCE,
                      limit: float = ATTACK_LIMIT) -> float | None:
    """Time from the first slip until Helmholtz motion, s.

    Helmholtz motion starts at the first onset followed by ``periods`` consecutive
    intervals within ``tolerance`` (relative) of the nominal period ``1 / frequency``.

    Parameters
    ----------
    onset_times : np.ndarray [shape=(n,)], s
        Increasing slip-onset times.
    frequency : float, Hz
        Nominal frequency of the (stopped) string.
    periods : int
    tolerance : float
    limit : float, s
        Later starts count as not reached.

    Returns
    -------
    float or None
        None when not reached within ``limit`` of the first slip.
    """
    times = np.asarray(onset_times, dtype=float)
    good = np.abs(np.diff(times) * frequency - 1.0) < tolerance
    if good.size < periods:
        return None
    runs = np.convolve(good.astype(int), np.ones(periods, int), mode="valid")
    starts = np.flatnonzero(runs == periods)
    if not starts.size:
        return None
    elapsed = float(times[starts[0]] - times[0])
    return elapsed if elapsed <= limit else None


def open_frequency(instrument: str, string: int) -> float:
    """Nominal (equal-tempered) frequency of an open string, Hz."""
    midi = instrument_facts(instrument).open_strings[string]
    return float(limits().tuning_a4 * 2.0 ** ((midi - 69) / 12.0))


@dataclass(frozen=True)
class Attack:
    """A bow start from rest at constant acceleration and force.

    Attributes
    ----------
    acceleration : float, m/s^2
    bow_force : float, N
    first_slip : float or None, s
        First slip after the bow starts (None: none within :data:`FIRST_SLIP_LIMIT`).
    time_to_helmholtz : float or None, s
        From the first slip until Helmholtz motion (:func:`time_to_helmholtz`).
    """

    acceleration: float
    bow_force: float
    first_slip: float | None
    time_to_helmholtz: float | None


def guettler_attack(instrument: str, string: int, acceleration: float, bow_force: float, *,
                    beta: float = 0.1, max_velocity: float = 1.0, seed: int = 0) -> Attack:
    """Start the bow from rest and measure the attack (no body).

    The bow is first set on the string with ``bow_force`` for one short block at rest;
    then its velocity is ``acceleration * t`` (capped at ``max_velocity``, m/s) at the end
    of each :data:`HOP`-sample block. The run stops once Helmholtz motion is found, or
    :data:`ATTACK_LIMIT` plus a few periods after the first slip.
    """
    inst = Instrument(instrument, body=None, seed=seed)
    rate = inst.sample_rate
    inst.process(64, {string: BowControl(0.0, bow_force, beta)})
    start = inst.time
    frequency = open_frequency(instrument, string)
    stop = start + FIRST_SLIP_LIMIT
    onsets: list[np.ndarray] = []
    first = None
    while inst.time < stop:
        velocity = min(acceleration * (inst.time + HOP / rate - start), max_velocity)
        times = inst.process(HOP, {string: BowControl(velocity, bow_force, beta)}
                             ).diagnostics[string].onset_times
        onsets.append(times)
        if first is None and times.size:
            first = float(times[0])
            stop = first + ATTACK_LIMIT + (ATTACK_PERIODS + 2) / frequency
        if first is not None and time_to_helmholtz(np.concatenate(onsets), frequency) is not None:
            break
    found = time_to_helmholtz(np.concatenate(onsets), frequency) if first is not None else None
    return Attack(float(acceleration), float(bow_force),
                  None if first is None else first - start, found)


def attack_grid(accelerations: Sequence[float], forces: Sequence[float]) -> list[tuple]:
    """``(acceleration, force)`` pairs of a Guettler map, force-major."""
    return [(float(a), float(f)) for f in forces for a in accelerations]


def perfect_window(attacks: Sequence[Attack], bow_force: float) -> tuple[float, float] | None:
    """Lowest and highest acceleration (m/s^2) with a perfect attack at ``bow_force``."""
    good = [a.acceleration for a in attacks if a.bow_force == bow_force
            and a.time_to_helmholtz is not None and a.time_to_helmholtz < PERFECT_ATTACK]
    return (min(good), max(good)) if good else None
