"""A simulated violinist: recording scripts in, bowing recordings and ground truth out.

No public bowing data set can be had offline, so the database is trained and tested on
recordings from this performer. It plays scripts of scales and short exercises (like the
recording scripts of Maestre et al. 2010) that cover the articulations x five dynamics x
contexts (slur position, run position, tempo) x four strings, with

- contours per technique (``../shared/reference/gestures.md``): detache, legato, staccato,
  spiccato (one bounce per note, force 0 between notes) and martele (force before motion);
- bow changes that reverse the velocity with a realistic acceleration (6-30 m/s^2);
- bow planning inside the 0.65 m hair (strokes scaled down to fit, retakes in rests with the
  bow lifted);
- context effects (slur and run position, tempo, note length) and vibrato;
- performer styles, trial-to-trial variability, timing deviations and sensor noise.

Every random draw comes from a :class:`numpy.random.Generator`. The exact boundaries played
go into the annotation's ``true_onset`` / ``true_offset``; its ``onset`` / ``offset`` carry a
coarse-alignment error of tens of milliseconds, as a score-to-recording alignment would.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.annotation import validate_annotation, write_annotation
from data_schemas.recording import (
    BOW_LENGTH,
    RECORDING_FRAME_RATE,
    validate_recording,
    write_recording,
)

#: MIDI pitches of the open violin strings G, D, A, E.
OPEN_STRINGS = (55, 62, 69, 76)
#: Vibrating length of an open violin string (m).
STRING_LENGTH = 0.325
#: The five dynamics of the recording scripts (levels of the notes table: 0 = pppp, 5 = mf).
SCRIPT_DYNAMICS = (2.0, 3.0, 5.0, 6.0, 7.0)
TECHNIQUES = ("detache", "legato", "staccato", "spiccato", "martele")

# Starting values per dynamic level (gestures.md): level, v (m/s), F (N), beta.
_DYN_LEVEL = np.array([0.0, 2.0, 3.0, 5.0, 6.0, 7.0, 9.0])
_DYN_V = np.array([0.06, 0.10, 0.17, 0.30, 0.45, 0.65, 0.85])
_DYN_F = np.array([0.10, 0.20, 0.35, 0.60, 1.10, 1.70, 2.30])
_DYN_BETA = np.array([0.19, 0.16, 0.125, 0.10, 0.08, 0.06, 0.05])

_MAJOR = (0, 2, 4, 5, 7, 9, 11, 12)
# Note durations (s) per technique: (shortest, longest).
_DURATIONS = {"detache": (0.22, 0.9), "legato": (0.2, 0.7), "staccato": (0.2, 0.5),
              "spiccato": (0.1, 0.2), "martele": (0.25, 0.6)}


def dynamic_values(dynamic: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Typical bow velocity (m/s), force (N) and beta for a dynamic level (0-9)."""
    d = np.asarray(dynamic, dtype=float)
    return (np.interp(d, _DYN_LEVEL, _DYN_V), np.interp(d, _DYN_LEVEL, _DYN_F),
            np.interp(d, _DYN_LEVEL, _DYN_BETA))


def finger_ratio(midi_pitch: np.ndarray | int, string: np.ndarray | int) -> np.ndarray:
    """Finger ratio ``1 - 2**(-semitones/12)`` of a pitch on a violin string (0 = G)."""
    semis = np.asarray(midi_pitch, float) - np.asarray(OPEN_STRINGS, float)[np.asarray(string)]
    return 1.0 - 2.0 ** (-np.maximum(semis, 0.0) / 12.0)


@dataclass(frozen=True)
class Performer:
    """The style of a simulated performer.

    Parameters
    ----------
    name : str
        Label written to the annotation.
    velocity_scale, force_scale, beta_scale : float
        Multipliers of the per-dynamic starting values.
    accel : float
        Typical bow-change acceleration (m/s^2), within 6-30.
    martele_accel : float
        Attack acceleration of martele strokes (m/s^2).
    variability : float
        Relative standard deviation of trial-to-trial variation of velocity, force, beta.
    ioi_sd : float
        Relative standard deviation of inter-onset intervals (timing deviations).
    tempo_scale : float
        Overall tempo factor applied to note durations (> 1 = slower).
    force_dip : float
        Relative dip of the force at a bow change.
    vibrato : float
        Vibrato depth (semitones, peak) on long detache and legato notes.
    staccato_fill : float
        Fraction of a staccato note during which the bow moves.
    finger_lead : float
        How long before a bow change the finger moves (s, mean).
    """

    name: str
    velocity_scale: float = 1.0
    force_scale: float = 1.0
    beta_scale: float = 1.0
    accel: float = 14.0
    martele_accel: float = 26.0
    variability: float = 0.08
    ioi_sd: float = 0.03
    tempo_scale: float = 1.0
    force_dip: float = 0.15
    vibrato: float = 0.12
    staccato_fill: float = 0.5
    finger_lead: float = 0.012


#: Three contrasting styles; further performers are random variations of these.
PERFORMERS = (
    Performer("steady"),
    Performer("energetic", velocity_scale=1.2, force_scale=1.15, beta_scale=0.9, accel=20.0,
              martele_accel=30.0, variability=0.1, ioi_sd=0.04, tempo_scale=0.92,
              force_dip=0.2, vibrato=0.15, staccato_fill=0.42, finger_lead=0.008),
    Performer("gentle", velocity_scale=0.85, force_scale=0.85, beta_scale=1.1, accel=9.0,
              martele_accel=22.0, variability=0.07, ioi_sd=0.025, tempo_scale=1.1,
              force_dip=0.1, vibrato=0.1, staccato_fill=0.58, finger_lead=0.018),
)


def make_performers(n: int, rng: np.random.Generator) -> list[Performer]:
    """Return ``n`` performer styles: the three :data:`PERFORMERS`, then random variants."""
    out = list(PERFORMERS[:n])
    while len(out) < n:
        base = PERFORMERS[len(out) % len(PERFORMERS)]
        out.append(replace(
            base, name=f"{base.name}{len(out)}",
            velocity_scale=base.velocity_scale * float(np.exp(rng.normal(0, 0.1))),
            force_scale=base.force_scale * float(np.exp(rng.normal(0, 0.1))),
            beta_scale=base.beta_scale * float(np.exp(rng.normal(0, 0.05))),
            accel=float(np.clip(base.accel * np.exp(rng.normal(0, 0.15)), 7.0, 25.0)),
            tempo_scale=base.tempo_scale * float(np.exp(rng.normal(0, 0.05)))))
    return out


# --------------------------------------------------------------------------- scripts


def recording_script(n_notes: int, rng: np.random.Generator) -> pd.DataFrame:
    """Generate a recording script of scales and short exercises.

    Exercises cycle through every technique x five dynamics x four strings (shuffled) and
    split their notes into runs separated by rests and, for legato, into slurs of 2-4 notes,
    so every slur and run position occurs.

    Parameters
    ----------
    n_notes : int
        Number of notes (the last exercise is cut to fit).
    rng : numpy.random.Generator
        Random source.

    Returns
    -------
    pandas.DataFrame
        One row per note: ``exercise``, ``run``, ``onset`` (nominal, s), ``duration`` (s),
        ``rest_after`` (s), ``midi_pitch``, ``string``, ``finger_ratio``, ``dynamic``,
        ``technique``, ``slur_position``, ``run_position``, ``tempo_bpm``.
    """
    combos = [(t, d, s) for t in TECHNIQUES for d in SCRIPT_DYNAMICS for s in range(4)]
    rows: list[dict] = []
    time = 0.5
    exercise = 0
    run_id = 0
    while len(rows) < n_notes:
        order = rng.permutation(len(combos))
        for k in order:
            if len(rows) >= n_notes:
                break
            technique, dynamic, string = combos[k]
            lo, hi = _DURATIONS[technique]
            dur = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
            pitches, strings = _exercise_pitches(technique, string, rng)
            pitches = pitches[: n_notes - len(rows)]
            strings = strings[: len(pitches)]
            runs = _split_runs(len(pitches), technique, rng)
            beat = dur if dur >= 0.3 else 2 * dur
            idx = 0
            for r, length in enumerate(runs):
                positions = _positions(length)
                slurs = (_slur_positions(length, rng) if technique == "legato"
                         else ["iso"] * length)
                for j in range(length):
                    last = j == length - 1
                    rest = 0.0
                    if last:
                        rest = 1.3 if r == len(runs) - 1 else max(beat, 0.35)
                    rows.append(dict(
                        exercise=exercise, run=run_id, onset=time, duration=dur,
                        rest_after=rest, midi_pitch=int(pitches[idx]),
                        string=int(strings[idx]), dynamic=dynamic, technique=technique,
                        slur_position=slurs[j], run_position=positions[j],
                        tempo_bpm=60.0 / beat))
                    time += dur + rest
                    idx += 1
                run_id += 1
            exercise += 1
    frame = pd.DataFrame(rows)
    frame["finger_ratio"] = finger_ratio(frame["midi_pitch"].to_numpy(),
                                         frame["string"].to_numpy())
    return frame


def _exercise_pitches(technique: str, string: int, rng: np.random.Generator):
    """Pitches and strings of one exercise: a scale on one string or a two-string pattern."""
    n = int(rng.integers(8, 17))
    if rng.random() < 0.75 or string == 3:
        start = int(rng.integers(0, 3))
        steps = list(_MAJOR[start:]) + list(_MAJOR[::-1][1:])
        root = int(rng.choice([0, 1, 2]))
        semis = [root + s for s in steps]
        semis = (semis * 3)[:n]
        strings = [string] * len(semis)
        pitches = [OPEN_STRINGS[string] + s for s in semis]
    else:  # string crossings with the string above
        pattern = [(string, 0), (string, 4), (string + 1, 0), (string + 1, 3), (string + 1, 5),
                   (string + 1, 3), (string + 1, 0), (string, 5)]
        pat = (pattern * 3)[:n]
        strings = [s for s, _ in pat]
        pitches = [OPEN_STRINGS[s] + k for s, k in pat]
    if technique == "legato":  # no repeated pitch inside a slur
        pitches = [p + (1 if i and p == pitches[i - 1] else 0) for i, p in enumerate(pitches)]
    return np.array(pitches), np.array(strings)


def _split_runs(n: int, technique: str, rng: np.random.Generator) -> list[int]:
    """Split ``n`` notes into runs without rests (lengths 1-8; legato runs >= 2)."""
    runs: list[int] = []
    left = n
    while left > 0:
        choices = [2, 3, 4, 6, 8] if technique == "legato" else [1, 2, 3, 4, 6, 8]
        length = min(int(rng.choice(choices)), left)
        if technique == "legato" and length == 1 and runs:
            runs[-1] += 1
        else:
            runs.append(length)
        left -= length
    return runs


def _positions(length: int) -> list[str]:
    if length == 1:
        return ["iso"]
    return ["init"] + ["mid"] * (length - 2) + ["end"]


def _slur_positions(length: int, rng: np.random.Generator) -> list[str]:
    out: list[str] = []
    left = length
    while left > 0:
        size = min(int(rng.integers(2, 5)), left)
        if left - size == 1:
            size += 1
        out += _positions(size) if size > 1 else ["iso"]
        left -= size
    return out


# --------------------------------------------------------------------------- performance


def perform(script: pd.DataFrame, performer: Performer, rng: np.random.Generator, *,
            frame_rate: float = RECORDING_FRAME_RATE,
            recording_id: str = "take") -> tuple[pd.DataFrame, pd.DataFrame]:
    """Play a recording script.

    Parameters
    ----------
    script : pandas.DataFrame
        From :func:`recording_script` (needs ``run``, ``duration``, ``rest_after``,
        ``midi_pitch``, ``string``, ``finger_ratio``, ``dynamic``, ``technique``,
        ``slur_position``, ``run_position``).
    performer : Performer
        Style.
    rng : numpy.random.Generator
        Random source.
    frame_rate : float
        Frames per second, 200-240 Hz.
    recording_id : str
        Take identifier written to both tables.

    Returns
    -------
    recording : pandas.DataFrame
        The :data:`data_schemas.recording.RECORDING` frames.
    annotation : pandas.DataFrame
        The :data:`data_schemas.annotation.ANNOTATION` rows with ground truth.
    """
    plan = _plan_notes(script, performer, rng)
    total = float(plan["stop"].max()) + 1.0
    t = np.arange(0.0, total, 1.0 / frame_rate)
    sig = _render(plan, performer, rng, t)
    rec = _add_noise(sig, rng)
    rec["recording_id"] = recording_id
    rec["time"] = t
    recording = validate_recording(pd.DataFrame(rec), source=recording_id)
    annotation = _annotation(plan, performer, rng, recording_id)
    return recording, annotation


def _plan_notes(script: pd.DataFrame, perf: Performer, rng: np.random.Generator) -> pd.DataFrame:
    """True timing, bow directions and per-note magnitudes."""
    plan = script.reset_index(drop=True).copy()
    n = len(plan)
    tech = plan["technique"].to_numpy()
    dur = plan["duration"].to_numpy() * perf.tempo_scale
    on = np.empty(n)
    true_dur = dur * np.exp(rng.normal(0.0, perf.ioi_sd, n))
    true_dur = np.maximum(true_dur, 0.7 * dur)
    rest = plan["rest_after"].to_numpy() * perf.tempo_scale
    tcur = 0.6
    for i in range(n):
        on[i] = tcur
        tcur += true_dur[i] + rest[i] * float(np.exp(rng.normal(0, 0.1)))
    run = plan["run"].to_numpy()
    run_end = np.r_[run[1:] != run[:-1], True]
    nxt = np.r_[on[1:], np.inf]
    # end of bow motion of each note
    fill = np.clip(perf.staccato_fill * np.exp(rng.normal(0, 0.08, n)), 0.3, 0.75)
    stop = np.where(run_end, on + true_dur * rng.uniform(0.9, 0.97, n), nxt)
    stop = np.where(tech == "staccato", on + fill * true_dur, stop)
    stop = np.where(tech == "martele", on + np.clip(fill + 0.15, 0.45, 0.85) * true_dur, stop)
    stop = np.where((tech == "spiccato") & run_end, on + true_dur * 0.95, stop)
    # bow directions: one stroke per note, one per slur for legato; alternate per exercise
    new_stroke = (tech != "legato") | plan["slur_position"].isin(["init", "iso"]).to_numpy()
    ex = plan["exercise"].to_numpy()
    direction = np.empty(n)
    d = 1.0
    for i in range(n):
        if i == 0 or ex[i] != ex[i - 1]:
            d = 1.0
        elif new_stroke[i]:
            d = -d
        direction[i] = d
    v, f, b = dynamic_values(plan["dynamic"].to_numpy())
    var = perf.variability
    length_factor = np.clip((0.4 / true_dur) ** 0.35, 0.6, 1.7)
    tech_v = pd.Series(tech).map({"detache": 1.0, "legato": 0.9, "staccato": 1.3,
                                   "spiccato": 0.8, "martele": 1.4}).to_numpy()
    vel = v * perf.velocity_scale * length_factor * tech_v * np.exp(rng.normal(0, var, n))
    # a staccato / spiccato burst cannot exceed the acceleration the arm can give
    burst = np.where(tech == "staccato", fill * true_dur, true_dur)
    limit = np.where(np.isin(tech, ("staccato", "spiccato")), 28.0 * burst / np.pi, np.inf)
    vel = np.minimum(vel, limit)
    fr = plan["finger_ratio"].to_numpy()
    force = f * perf.force_scale * np.exp(rng.normal(0, var, n))
    slur = plan["slur_position"].to_numpy()
    force *= np.where(slur == "init", 1.05, np.where(slur == "end", 0.92, 1.0))
    beta = b * perf.beta_scale * np.exp(rng.normal(0, var, n)) / np.sqrt(1.0 - fr)
    accel = np.clip(perf.accel * np.exp(rng.normal(0, 0.15, n)), 6.0, 30.0)
    accel = np.where(tech == "martele",
                     np.clip(perf.martele_accel * np.exp(rng.normal(0, 0.1, n)), 15.0, 30.0),
                     accel)
    plan = plan.assign(on=on, true_dur=true_dur, stop=stop, nxt=nxt, run_end=run_end,
                       direction=direction, vel=vel, force=force,
                       beta=np.clip(beta, 0.03, 0.3), accel=accel, fill=fill,
                       new_stroke=new_stroke)
    # true offsets: the next onset inside a run, the end of bow motion at a run's end
    plan["true_offset"] = np.where(run_end, stop, nxt)
    return plan


def _render(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator,
            t: np.ndarray) -> dict[str, np.ndarray]:
    """Noise-free signals on the frame grid ``t``."""
    fs = 1.0 / (t[1] - t[0])
    n_frames = t.size
    v = np.zeros(n_frames)
    force = np.zeros(n_frames)
    beta = np.full(n_frames, float(plan["beta"].iloc[0]))
    semis = np.zeros(n_frames)
    string = np.full(n_frames, int(plan["string"].iloc[0]), dtype=np.int8)

    def sl(a: float, b: float) -> slice:
        return slice(max(int(np.ceil(a * fs)), 0), min(int(np.ceil(b * fs)), n_frames))

    tech = plan["technique"].to_numpy()
    n = len(plan)
    on = plan["on"].to_numpy()
    stop = plan["stop"].to_numpy()
    run = plan["run"].to_numpy()
    semitone = plan["midi_pitch"].to_numpy() - np.asarray(OPEN_STRINGS)[plan["string"]]
    # ---- velocity and force, stroke by stroke
    i = 0
    while i < n:
        j = i + 1  # one stroke: a legato slur, otherwise one note
        if tech[i] == "legato":
            while j < n and run[j] == run[i] and not plan["new_stroke"].iloc[j]:
                j += 1
        _stroke(plan, i, j, t, v, force, sl, rng, perf)
        i = j
    # ---- bow planning: per run, fit the travel inside the hair; retakes in the rests
    pos = np.zeros(n_frames)
    runs = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    prev_end_pos = 0.1
    prev_stop_frame = 0
    for k, first in enumerate(runs):
        last = (runs[k + 1] if k + 1 < len(runs) else n) - 1
        s = sl(on[first] - 0.12, stop[last] + 0.1)
        travel = np.cumsum(v[s]) / fs / BOW_LENGTH
        span = travel.max() - travel.min()
        if span > 0.92:
            v[s] *= 0.92 / span
            force[s] *= 1.0 + 0.3 * (1 - 0.92 / span)
            travel *= 0.92 / span
        want = 0.12 if plan["direction"].iloc[first] > 0 else 0.88
        lo, hi = 0.04 - travel.min(), 0.96 - travel.max()
        start = float(np.clip(want - travel[0], lo, hi))
        # a retake in a short rest can only move the lifted bow so far (peak 1.5 m/s)
        reach = 1.5 * max(s.start - prev_stop_frame, 0) / fs / (0.5 * np.pi) / BOW_LENGTH
        if k > 0:
            start = float(np.clip(start, prev_end_pos - travel[0] - reach,
                                  prev_end_pos - travel[0] + reach))
            start = float(np.clip(start, lo, hi)) if lo <= hi else start
        pos[s] = start + travel
        # retake: the lifted bow moves from the previous end to this start
        a, b = prev_stop_frame, s.start
        if b > a:
            ramp = 0.5 - 0.5 * np.cos(np.pi * np.linspace(0.0, 1.0, b - a))
            delta = pos[s.start] - prev_end_pos
            pos[a:b] = prev_end_pos + delta * ramp
            if abs(delta) > 0.02 and a > 0:
                v[a:b] += np.gradient(pos[a:b]) * fs * BOW_LENGTH
        prev_end_pos = pos[s.stop - 1]
        prev_stop_frame = s.stop
    pos[prev_stop_frame:] = prev_end_pos
    # ---- left hand: finger and string change slightly before the bow (legato: at the onset)
    lead = np.where(tech == "legato", 0.0,
                    np.clip(rng.normal(perf.finger_lead, 0.004, n), 0.0, 0.03))
    lead = np.where(plan["run_position"].isin(["init", "iso"]).to_numpy(),
                    rng.uniform(0.06, 0.2, n), lead)
    change = on - lead
    for i in range(n):
        end = change[i + 1] if i + 1 < n else t[-1] + 1
        s = sl(change[i], end)
        semis[s] = semitone[i]
        string[s] = plan["string"].iloc[i]
        if plan["true_dur"].iloc[i] > 0.3 and tech[i] in ("detache", "legato"):
            tt = t[s] - change[i]
            depth = perf.vibrato * np.clip((tt - 0.12) / 0.15, 0.0, 1.0)
            semis[s] += depth * np.sin(2 * np.pi * 5.5 * tt + rng.uniform(0, 2 * np.pi))
        # beta glides to the note's value in ~40 ms, with a slow drift
        tt = t[s] - change[i]
        target = plan["beta"].iloc[i] * (1 + 0.05 * rng.normal() * tt)
        start_beta = beta[s.start - 1] if s.start > 0 else target
        w = np.clip(tt / 0.04, 0.0, 1.0)
        beta[s] = start_beta + (target - start_beta) * w
    fr = 1.0 - 2.0 ** (-np.maximum(semis, 0.0) / 12.0)
    return dict(bow_velocity=v, bow_force=force, beta=np.clip(beta, 0.02, 0.4),
                bow_position=pos, string=string, finger_ratio=fr)


def _stroke(plan, i: int, j: int, t, v, force, sl, rng, perf: Performer) -> None:
    """Write one bow stroke (notes ``i..j-1``) into ``v`` and ``force``."""
    row = plan.iloc[i]
    tech = row["technique"]
    d = row["direction"]
    on0 = row["on"]
    end = plan["stop"].iloc[j - 1]
    run_init = row["run_position"] in ("init", "iso")
    run_end = bool(plan["run_end"].iloc[j - 1])
    if tech in ("detache", "legato"):
        s = sl(on0, end)
        tt = t[s]
        V = plan["vel"].iloc[i:j].mean()
        acc = plan["accel"].iloc[i]
        ramp_up = min(np.pi * V / (2 * acc), 0.35 * (end - on0))
        ramp_dn = min(np.pi * V / (2 * acc * rng.uniform(0.8, 1.2)), 0.35 * (end - on0))
        u = (tt - on0) / (end - on0)
        shape = (1 + rng.normal(0, 0.12) * (u - 0.5)) * np.sin(
            0.5 * np.pi * np.clip((tt - on0) / ramp_up, 0, 1)) * np.sin(
            0.5 * np.pi * np.clip((end - tt) / ramp_dn, 0, 1))
        v[s] = d * V * shape
        # force: per note, continuous inside the stroke, dips at the bow change
        F = np.interp(tt, plan["on"].iloc[i:j].to_numpy(), plan["force"].iloc[i:j].to_numpy())
        F *= 1 - perf.force_dip * (np.exp(-((tt - on0) / 0.03) ** 2)
                                   + np.exp(-((tt - end) / 0.03) ** 2))
        force[s] = F
        _contact_edges(t, force, sl, on0, end, F[0], F[-1], run_init, run_end)
        return
    note_on = row["on"]
    stop = row["stop"]
    V = row["vel"]
    F0 = row["force"]
    if tech == "staccato":
        s = sl(note_on, stop)
        tt = t[s]
        v[s] = d * V * np.sin(np.pi * (tt - note_on) / (stop - note_on))
        held_end = plan["nxt"].iloc[i] if not run_end else stop
        sh = sl(note_on, held_end)
        force[sh] = F0 * (1 + 0.15 * np.exp(-((t[sh] - note_on) / 0.04) ** 2))
        _contact_edges(t, force, sl, note_on, held_end, F0, F0, run_init, run_end)
    elif tech == "martele":
        s = sl(note_on, stop)
        tt = t[s]
        rise = np.pi * V / (2 * row["accel"])
        body = np.where(tt - note_on < rise,
                        np.sin(0.5 * np.pi * np.clip((tt - note_on) / rise, 0, 1)),
                        np.clip((stop - tt) / max(stop - note_on - rise, 1e-3), 0, 1) ** 0.8)
        v[s] = d * V * body
        pre = rng.uniform(0.04, 0.07)
        held_end = plan["nxt"].iloc[i] if not run_end else stop + 0.05
        sf = sl(note_on - pre, held_end)
        tf = t[sf]
        build = np.clip((tf - note_on + pre) / pre, 0, 1)
        release = 0.25 + 1.35 * np.exp(-np.maximum(tf - note_on, 0) / 0.08)
        base = 0.0 if run_init else 0.25 * F0
        force[sf] = np.maximum(force[sf], base + (F0 * release - base) * build)
        if run_end:
            se = sl(stop, stop + 0.08)
            force[se] *= np.clip((stop + 0.08 - t[se]) / 0.08, 0, 1)
    else:  # spiccato: one bounce per note, force 0 between notes
        s = sl(note_on, stop)
        tt = t[s]
        u = (tt - note_on) / (stop - note_on)
        v[s] = d * V * np.sin(np.pi * u)
        alpha = rng.normal(0.0, 0.3)
        c = 0.3
        g = -np.cos(2 * np.pi * u - alpha)
        force[s] = 1.4 * F0 * np.maximum(0.0, (g - c) / (1 - c))


def _contact_edges(t, force, sl, start, end, f_start, f_end, run_init, run_end) -> None:
    """Put the bow on the string before a run and lift it after."""
    if run_init:
        s = sl(start - 0.08, start)
        force[s] = f_start * np.clip((t[s] - start + 0.08) / 0.06, 0, 1)
    if run_end:
        s = sl(end, end + 0.06)
        force[s] = f_end * np.clip((end + 0.06 - t[s]) / 0.06, 0, 1)


def _add_noise(sig: dict[str, np.ndarray], rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Sensor noise of a motion-capture and strain-gauge setup."""
    n = sig["bow_velocity"].size
    out = dict(sig)
    out["bow_velocity"] = sig["bow_velocity"] + rng.normal(0, 0.004, n)
    out["bow_force"] = np.abs(sig["bow_force"] + rng.normal(0, 0.008, n))
    out["beta"] = np.clip(sig["beta"] + rng.normal(0, 0.0015, n), 0.01, 0.45)
    out["bow_position"] = np.clip(sig["bow_position"] + rng.normal(0, 0.001, n), 0.0, 1.0)
    out["finger_ratio"] = np.clip(sig["finger_ratio"] + rng.normal(0, 0.0003, n), 0.0, 0.8)
    return out


def _annotation(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator,
                recording_id: str) -> pd.DataFrame:
    n = len(plan)
    # coarse-alignment error: slowly varying (sd ~30 ms) plus per-note jitter (sd 10 ms)
    drift = np.zeros(n)
    for i in range(1, n):
        drift[i] = 0.9 * drift[i - 1] + rng.normal(0, 0.013)
    err = drift + rng.normal(0, 0.01, n)
    onset = np.maximum(plan["on"].to_numpy() + err, 0.0)
    onset = np.maximum.accumulate(onset)
    offset = np.maximum(plan["true_offset"].to_numpy() + np.r_[err[1:], err[-1]], onset + 0.02)
    frame = pd.DataFrame(dict(
        recording_id=recording_id, note_index=np.arange(n, dtype=np.int32), onset=onset,
        offset=offset, midi_pitch=plan["midi_pitch"], string=plan["string"],
        finger_ratio=plan["finger_ratio"], dynamic=plan["dynamic"],
        technique=plan["technique"],
        bow_direction=np.where(plan["direction"] > 0, "down", "up"),
        slur_position=plan["slur_position"], run_position=plan["run_position"],
        tempo_bpm=plan["tempo_bpm"], performer=perf.name,
        true_onset=plan["on"], true_offset=plan["true_offset"]))
    return validate_annotation(frame, source=recording_id)


# --------------------------------------------------------------------------- sessions


def simulate_recordings(n_notes: int, n_performers: int, out_dir: str | Path, *, seed: int = 0,
                        notes_per_take: int = 500,
                        frame_rate: float = RECORDING_FRAME_RATE,
                        progress: bool = False) -> list[Path]:
    """Simulate a recording session and write one recording + annotation per take.

    Parameters
    ----------
    n_notes : int
        Total number of notes over all performers.
    n_performers : int
        Number of performer styles (see :func:`make_performers`).
    out_dir : path-like
        Output directory; takes are ``<performer>_take<k>.parquet`` with
        ``<performer>_take<k>.annotation.parquet`` beside them.
    seed : int
        Seed of the :class:`numpy.random.Generator`.
    notes_per_take : int
        Notes per take file.
    frame_rate : float
        Frames per second (200-240 Hz).
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of pathlib.Path
        The recording files written.
    """
    from data_schemas.errors import ParameterError

    if n_notes < 1 or n_performers < 1:
        raise ParameterError(f"n_notes={n_notes} and n_performers={n_performers} must be >= 1")
    if not 200.0 <= frame_rate <= 240.0:
        raise ParameterError(f"frame_rate={frame_rate} Hz is outside 200-240 Hz")
    rng = np.random.default_rng(seed)
    performers = make_performers(n_performers, rng)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    per = [n_notes // n_performers + (1 if k < n_notes % n_performers else 0)
           for k in range(n_performers)]
    jobs = []
    for perf, count in zip(performers, per, strict=True):
        take = 0
        while count > 0:
            size = min(notes_per_take, count)
            jobs.append((perf, take, size))
            count -= size
            take += 1
    seeds = rng.integers(0, 2**63 - 1, len(jobs))
    paths = []
    from tqdm import tqdm

    for (perf, take, size), job_seed in tqdm(list(zip(jobs, seeds, strict=True)),
                                             desc="simulate", unit="take",
                                             disable=not progress):
        job_rng = np.random.default_rng(int(job_seed))
        rid = f"{perf.name}_take{take:03d}"
        script = recording_script(size, job_rng)
        recording, annotation = perform(script, perf, job_rng, frame_rate=frame_rate,
                                        recording_id=rid)
        path = out / f"{rid}.parquet"
        write_annotation(annotation, out / f"{rid}.annotation.parquet")
        write_recording(recording, path)
        paths.append(path)
    return paths


__all__ = ["OPEN_STRINGS", "PERFORMERS", "SCRIPT_DYNAMICS", "STRING_LENGTH", "TECHNIQUES",
           "Performer", "dynamic_values", "finger_ratio", "make_performers", "perform",
           "recording_script", "simulate_recordings"]
