"""The simulated player's left hand: intonation, vibrato and shifts, as a contour in cents.

:func:`left_hand_contour` gives, for every frame, the deviation (cents) of the stopped pitch
from the nominal pitch of the note being played; :func:`gesture_db.playing.play_script`
adds it to the finger (``finger_ratio``) and records it as ``pitch_deviation_cents``. At
the recording's 200-240 Hz frame rate a 4.5-7 Hz vibrato has 30-50 frames per cycle, so the
contour represents it faithfully. Per note (constants ``[left_hand]`` of
``gesture_db/config/simulate.toml``, style the :class:`~gesture_db.simulate_config.Performer`):

- **intonation**: an offset drawn from N(0, ``intonation_sd``) on stopped notes (open
  strings cannot be re-tuned: 0);
- **vibrato** on stopped detache and legato notes longer than ``vibrato_min_duration``:
  rate ``vibrato_rate`` (Hz) and peak extent ``vibrato_extent`` (cents) of the performer,
  faster and wider with the dynamic (``dynamic_rate``, ``dynamic_extent`` per level above
  mf), wider on long notes (``length_extent`` on notes of 2 s and more) and on a phrase's
  last note (``phrase_end_extent``), varied per note (``rate_sd`` Hz, ``extent_sd`` log,
  ``delay_sd`` log); it starts ``vibrato_delay`` after the onset (at most
  ``max_delay_share`` of the note), reaches full depth over ``vibrato_rise``, swells by
  ``extent_swell`` and its rate drifts by ``rate_drift`` from the note's start to its end
  (around the note's middle, so the means are the drawn values); none on open strings;
- **shifts**: a slurred note on the same string in another hand position (positions
  ``shift_span`` semitones wide) is reached by sliding ``slide_share`` of the interval over
  the previous note's last ``shift_glide`` seconds (the performer's, per note
  ``glide_sd`` log), the rest a finger step at the onset (so the segmentation still sees a
  finger change there).

The truth per note (intonation, mean rate, mean full-depth extent) goes to the annotation.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from gesture_db.simulate_config import Performer, simulator_config

_MF = 5.0


def vibrato_plan(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator,
                 semitone: np.ndarray) -> dict[str, np.ndarray]:
    """Per-note intonation (cents), vibrato rate (Hz), extent (cents), delay (s) and glide.

    Parameters
    ----------
    plan : pandas.DataFrame
        The played notes (``true_dur``, ``technique``, ``dynamic``, ``run_position``,
        ``slur_position``, ``string``).
    perf : Performer
    rng : numpy.random.Generator
        The left hand's own random stream.
    semitone : np.ndarray [shape=(n,)]
        Semitones of each note above its open string (0 = open).

    Returns
    -------
    dict
        ``intonation``, ``rate`` (NaN without vibrato), ``extent`` (0 without), ``delay``
        and ``glide`` (s of slide at the note's end, 0 without a shift after it).
    """
    cfg = simulator_config()["left_hand"]
    n = len(plan)
    dur = plan["true_dur"].to_numpy(float)
    tech = plan["technique"].to_numpy()
    stopped = semitone > 0
    draws = rng.normal(0.0, 1.0, (n, 5))  # one row per note: the stream is stable
    intonation = np.where(stopped, np.clip(perf.intonation_sd * draws[:, 0],
                                           -cfg["max_intonation"], cfg["max_intonation"]), 0.0)
    vib = stopped & np.isin(tech, ("detache", "legato")) & (dur > cfg["vibrato_min_duration"])
    level = plan["dynamic"].to_numpy(float) - _MF
    long = np.clip((dur - 0.5) / 1.5, 0.0, 1.0)
    phrase_end = plan["run_position"].isin(["end", "iso"]).to_numpy()
    extent = (perf.vibrato_extent * (1.0 + cfg["dynamic_extent"] * level)
              * (1.0 + cfg["length_extent"] * long)
              * np.where(phrase_end, cfg["phrase_end_extent"], 1.0)
              * np.exp(cfg["extent_sd"] * draws[:, 1]))
    rate = perf.vibrato_rate + cfg["dynamic_rate"] * level + cfg["rate_sd"] * draws[:, 2]
    delay = np.minimum(perf.vibrato_delay * np.exp(cfg["delay_sd"] * draws[:, 3]),
                       cfg["max_delay_share"] * dur)
    glide = _glides(plan, perf, semitone, draws[:, 4])
    return dict(intonation=intonation,
                rate=np.where(vib, np.clip(rate, *cfg["rate_range"]), np.nan),
                extent=np.where(vib, np.clip(extent, *cfg["extent_range"]), 0.0),
                delay=delay, glide=glide)


def _glides(plan: pd.DataFrame, perf: Performer, semitone: np.ndarray,
            draw: np.ndarray) -> np.ndarray:
    """Slide (s) at the end of each note that is left by a shift (see the module doc)."""
    cfg = simulator_config()["left_hand"]
    n = len(plan)
    if n < 2:
        return np.zeros(n)
    string = plan["string"].to_numpy()
    slurred = (plan["technique"].to_numpy() == "legato") & \
        plan["slur_position"].isin(["mid", "end"]).to_numpy()
    position = np.floor(semitone / cfg["shift_span"])
    shift = np.r_[slurred[1:] & (string[1:] == string[:-1]) & (semitone[1:] > 0)
                  & (semitone[:-1] > 0) & (position[1:] != position[:-1]), False]
    glide = perf.shift_glide * np.exp(cfg["glide_sd"] * draw)
    return np.where(shift, np.minimum(glide, cfg["max_glide_share"]
                                      * plan["true_dur"].to_numpy(float)), 0.0)


def left_hand_contour(plan: pd.DataFrame, notes: dict[str, np.ndarray], semitone: np.ndarray,
                      t: np.ndarray, starts: np.ndarray, phases: np.ndarray) -> np.ndarray:
    """Pitch deviation (cents) per frame from the nominal pitch of the note being played.

    Parameters
    ----------
    plan : pandas.DataFrame
        The played notes (``on``, ``true_dur``).
    notes : dict
        :func:`vibrato_plan` output.
    semitone : np.ndarray [shape=(n,)]
        Semitones of each note above its open string.
    t : np.ndarray [shape=(m,)], s
        Frame times (uniform grid from 0).
    starts : np.ndarray [shape=(n,)], s
        When the finger moves to each note (its frames run to the next note's start).
    phases : np.ndarray [shape=(n,)], rad
        Vibrato phase at each note's onset.
    """
    cfg = simulator_config()["left_hand"]
    fs = 1.0 / (t[1] - t[0])
    on = plan["on"].to_numpy(float)
    dur = plan["true_dur"].to_numpy(float)
    n = len(plan)
    cents = np.zeros(t.size)
    first = np.clip(np.ceil(starts * fs).astype(int), 0, t.size)
    last = np.r_[first[1:], t.size]
    for i in range(n):
        s = slice(int(first[i]), int(max(last[i], first[i])))
        tt = t[s] - on[i]
        c = np.full(tt.size, notes["intonation"][i])
        if notes["extent"][i] > 0:
            pos = np.clip(tt / dur[i], 0.0, 1.0) - 0.5
            env = notes["extent"][i] * np.clip((tt - notes["delay"][i]) / cfg["vibrato_rise"],
                                               0.0, 1.0) * (1.0 + cfg["extent_swell"] * pos)
            rate = notes["rate"][i] + cfg["rate_drift"] * pos
            phase = phases[i] + 2.0 * np.pi * np.cumsum(rate) / fs
            c += env * np.sin(phase)
        g = notes["glide"][i]
        if g > 0 and i + 1 < n:
            end = starts[i + 1]
            w = np.clip((t[s] - (end - g)) / g, 0.0, 1.0)
            c += cfg["slide_share"] * 100.0 * (semitone[i + 1] - semitone[i]) \
                * w * w * (3.0 - 2.0 * w)
        cents[s] = c
    return cents


def measured_contour(cents: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The recorded contour: ``cents`` plus the pitch tracker's noise (``[noise]``)."""
    sd = simulator_config()["noise"]["pitch_deviation_cents"]
    return cents + rng.normal(0.0, sd, cents.size)


__all__ = ["left_hand_contour", "measured_contour", "vibrato_plan"]
