"""Bow-stroke contours of the simulated violinist: velocity and force of one stroke.

The shapes follow ``../shared/reference/gestures.md`` ("Articulations"); the constants are
``[stroke]`` of ``gesture_db/config/simulate.toml``. Used by :mod:`gesture_db.playing`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from gesture_db.simulate_config import Performer, simulator_config

Slicer = Callable[[float, float], slice]


def stroke(plan: pd.DataFrame, i: int, j: int, t: np.ndarray, v: np.ndarray,
           force: np.ndarray, sl: Slicer, rng: np.random.Generator, perf: Performer) -> None:
    """Write one bow stroke (notes ``i..j-1`` of ``plan``) into ``v`` (m/s) and ``force`` (N).

    Parameters
    ----------
    plan : pandas.DataFrame
        Planned notes (``technique``, ``direction``, ``on``, ``stop``, ``nxt``, ``run_end``,
        ``run_position``, ``vel``, ``force``, ``accel``).
    i, j : int
        First and one-past-last note of the stroke (a legato slur, else one note).
    t : np.ndarray [shape=(n_frames,)], s
        Frame times.
    v, force : np.ndarray [shape=(n_frames,)]
        Signals, written in place.
    sl : callable
        ``sl(a, b)`` -> the frames in [a, b).
    rng : numpy.random.Generator
    perf : Performer
    """
    row = plan.iloc[i]
    tech = row["technique"]
    if tech in ("detache", "legato"):
        _sustained(plan, i, j, t, v, force, sl, rng, perf)
    elif tech == "staccato":
        _staccato(plan, i, t, v, force, sl)
    elif tech == "martele":
        _martele(plan, i, t, v, force, sl, rng)
    else:
        _spiccato(row, t, v, force, sl, rng)


def _sustained(plan: pd.DataFrame, i: int, j: int, t: np.ndarray, v: np.ndarray,
               force: np.ndarray, sl: Slicer, rng: np.random.Generator,
               perf: Performer) -> None:
    """Detache or legato: rise, hold, fall to the bow change; force dips at the change."""
    cfg = simulator_config()["stroke"]
    row = plan.iloc[i]
    d = row["direction"]
    on0 = row["on"]
    end = plan["stop"].iloc[j - 1]
    run_init = row["run_position"] in ("init", "iso")
    run_end = bool(plan["run_end"].iloc[j - 1])
    s = sl(on0, end)
    tt = t[s]
    V = plan["vel"].iloc[i:j].mean()
    acc = plan["accel"].iloc[i]
    share = cfg["max_ramp_share"]
    ramp_up = min(np.pi * V / (2 * acc), share * (end - on0))
    ramp_dn = min(np.pi * V / (2 * acc * rng.uniform(*cfg["ramp_jitter"])), share * (end - on0))
    u = (tt - on0) / (end - on0)
    tilt = plan["tilt"].iloc[i] if "tilt" in plan else 0.0
    shape = (1 + (tilt + rng.normal(0, cfg["shape_sd"])) * (u - 0.5)) * np.sin(
        0.5 * np.pi * np.clip((tt - on0) / ramp_up, 0, 1)) * np.sin(
        0.5 * np.pi * np.clip((end - tt) / ramp_dn, 0, 1))
    v[s] = d * V * shape
    # force: per note, continuous inside the stroke, dips at the bow change
    F = np.interp(tt, plan["on"].iloc[i:j].to_numpy(), plan["force"].iloc[i:j].to_numpy())
    w = cfg["dip_width"]
    F *= 1 - perf.force_dip * (np.exp(-((tt - on0) / w) ** 2) + np.exp(-((tt - end) / w) ** 2))
    force[s] = F
    contact_edges(t, force, sl, on0, end, F[0], F[-1], run_init, run_end)


def _one_note(plan: pd.DataFrame, i: int) -> tuple:
    """Row ``i`` and its onset, stop (s), velocity (m/s), force (N), run start and run end."""
    row = plan.iloc[i]
    return (row, row["on"], row["stop"], row["vel"], row["force"],
            row["run_position"] in ("init", "iso"), bool(plan["run_end"].iloc[i]))


def _staccato(plan: pd.DataFrame, i: int, t: np.ndarray, v: np.ndarray, force: np.ndarray,
              sl: Slicer) -> None:
    """A velocity burst, then the bow rests on the string with the force kept."""
    cfg = simulator_config()["stroke"]
    row, note_on, stop, V, F0, run_init, run_end = _one_note(plan, i)
    s = sl(note_on, stop)
    tt = t[s]
    v[s] = row["direction"] * V * np.sin(np.pi * (tt - note_on) / (stop - note_on))
    held_end = plan["nxt"].iloc[i] if not run_end else stop
    sh = sl(note_on, held_end)
    force[sh] = F0 * (1 + cfg["staccato_accent"]
                      * np.exp(-((t[sh] - note_on) / cfg["staccato_accent_width"]) ** 2))
    contact_edges(t, force, sl, note_on, held_end, F0, F0, run_init, run_end)


def _martele(plan: pd.DataFrame, i: int, t: np.ndarray, v: np.ndarray, force: np.ndarray,
             sl: Slicer, rng: np.random.Generator) -> None:
    """Force before motion, a sharp attack, the force released after."""
    cfg = simulator_config()["stroke"]
    row, note_on, stop, V, F0, run_init, run_end = _one_note(plan, i)
    s = sl(note_on, stop)
    tt = t[s]
    rise = np.pi * V / (2 * row["accel"])
    body = np.where(tt - note_on < rise,
                    np.sin(0.5 * np.pi * np.clip((tt - note_on) / rise, 0, 1)),
                    np.clip((stop - tt) / max(stop - note_on - rise, 1e-3), 0, 1)
                    ** cfg["martele_decay_exponent"])
    v[s] = row["direction"] * V * body
    pre = rng.uniform(*cfg["martele_pre"])
    held_end = plan["nxt"].iloc[i] if not run_end else stop + cfg["martele_hold"]
    sf = sl(note_on - pre, held_end)
    tf = t[sf]
    build = np.clip((tf - note_on + pre) / pre, 0, 1)
    floor, peak = cfg["martele_release"]
    release = floor + peak * np.exp(-np.maximum(tf - note_on, 0) / cfg["martele_release_time"])
    base = 0.0 if run_init else cfg["martele_lift_force"] * F0
    force[sf] = np.maximum(force[sf], base + (F0 * release - base) * build)
    if run_end:
        fade = cfg["martele_fade"]
        se = sl(stop, stop + fade)
        force[se] *= np.clip((stop + fade - t[se]) / fade, 0, 1)


def _spiccato(row: pd.Series, t: np.ndarray, v: np.ndarray, force: np.ndarray, sl: Slicer,
              rng: np.random.Generator) -> None:
    """One bounce per note, force 0 between notes."""
    cfg = simulator_config()["stroke"]
    note_on, stop = row["on"], row["stop"]
    s = sl(note_on, stop)
    tt = t[s]
    u = (tt - note_on) / (stop - note_on)
    v[s] = row["direction"] * row["vel"] * np.sin(np.pi * u)
    alpha = rng.normal(0.0, cfg["spiccato_phase_sd"])
    c = cfg["spiccato_threshold"]
    g = -np.cos(2 * np.pi * u - alpha)
    force[s] = cfg["spiccato_peak"] * row["force"] * np.maximum(0.0, (g - c) / (1 - c))


def contact_edges(t: np.ndarray, force: np.ndarray, sl: Slicer, start: float, end: float,
                  f_start: float, f_end: float, run_init: bool, run_end: bool) -> None:
    """Put the bow on the string before a run and lift it after (``force`` in place)."""
    cfg = simulator_config()["stroke"]
    if run_init:
        lead = cfg["contact_lead"]
        s = sl(start - lead, start)
        force[s] = f_start * np.clip((t[s] - start + lead) / cfg["contact_ramp"], 0, 1)
    if run_end:
        lift = cfg["lift_time"]
        s = sl(end, end + lift)
        force[s] = f_end * np.clip((end + lift - t[s]) / lift, 0, 1)


__all__ = ["contact_edges", "stroke"]
