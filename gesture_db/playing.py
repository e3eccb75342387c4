"""The simulated player (violin, viola or cello) plays a script: bowing signals and truth.

:func:`play_script` turns a script (:func:`gesture_db.script.recording_script`) into a
recording and its annotation, with

- contours per technique (``../shared/reference/gestures.md``): detache, legato, staccato,
  spiccato (one bounce per note, force 0 between notes) and martele (force before motion);
- bow changes that reverse the velocity with a realistic acceleration (6-30 m/s^2);
- bow planning inside the violin's bow hair (runs scaled down to fit the bow-travel budget
  :class:`data_schemas.bow.BowBudget`, retakes in rests with the bow lifted);
- context effects: speed with note length and dynamic, force with dynamic and string (the
  caller's per-string force factors), contact point with bow speed (a slower bow nearer
  the bridge), a crescendo and an arch over each run with sustained notes tilting with
  the crescendo, accents on slur and run starts, the bow slowing before a leap and
  lightening before a string crossing;
- the left hand (:mod:`gesture_db.playing_left_hand`): intonation, vibrato and shifts in
  the finger and recorded as ``pitch_deviation_cents``, drawn from a stream of their own
  (``rng.spawn``) so the bowing signals are those the same seed gave before;
- performer styles, trial-to-trial variability, timing deviations and sensor noise.

Every random draw comes from a :class:`numpy.random.Generator`. The exact boundaries played
go into the annotation's ``true_onset`` / ``true_offset``; its ``onset`` / ``offset`` carry a
coarse-alignment error of tens of milliseconds, as a score-to-recording alignment would.
The constants are ``gesture_db/config/simulate.toml``'s; the strokes are
:mod:`gesture_db.strokes`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pandas as pd

from data_schemas.annotation import validate_annotation
from data_schemas.bow import BowBudget
from data_schemas.instruments import dynamics_table, finger_ratio, instrument_facts, limits
from data_schemas.recording import RECORDING, RECORDING_FRAME_RATE, validate_recording
from gesture_db.playing_left_hand import left_hand_contour, measured_contour, vibrato_plan
from gesture_db.script import INSTRUMENT
from gesture_db.simulate_config import Performer, simulator_config
from gesture_db.strokes import stroke

Slicer = Callable[[float, float], slice]


def play_script(script: pd.DataFrame, performer: Performer, rng: np.random.Generator, *,
                frame_rate: float = RECORDING_FRAME_RATE, recording_id: str = "take",
                force_factors: np.ndarray | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Play a recording script.

    Parameters
    ----------
    script : pandas.DataFrame
        From :func:`gesture_db.script.recording_script` (needs ``run``, ``duration``,
        ``rest_after``, ``midi_pitch``, ``string``, ``finger_ratio``, ``dynamic``,
        ``technique``, ``slur_position``, ``run_position``).
    performer : Performer
        Style.
    rng : numpy.random.Generator
        Random source.
    frame_rate : float
        Frames per second, 200-240 Hz.
    recording_id : str
        Take identifier written to both tables.
    force_factors : np.ndarray [shape=(4,)], optional
        Per string, the force the performer uses relative to the violinist's dynamics table
        (a cello's C string needs several times a violin string's force); default all 1.
        The instrument is the script's ``instrument`` column (default violin).

    Returns
    -------
    recording : pandas.DataFrame
        The :data:`data_schemas.recording.RECORDING` frames.
    annotation : pandas.DataFrame
        The :data:`data_schemas.annotation.ANNOTATION` rows with ground truth.
    """
    hand_rng = rng.spawn(1)[0]  # the left hand's own stream: the bow's draws stay as they were
    plan = _plan_notes(script, performer, rng, force_factors)
    hand = vibrato_plan(plan, performer, hand_rng, _semitones(plan))
    plan = plan.assign(**{f"lh_{k}": v for k, v in hand.items()})
    total = float(plan["stop"].max()) + 1.0
    t = np.arange(0.0, total, 1.0 / frame_rate)
    sig = _render(plan, performer, rng, t)
    rec = _add_noise(sig, rng)
    rec["pitch_deviation_cents"] = measured_contour(sig["pitch_deviation_cents"], hand_rng)
    rec["recording_id"] = recording_id
    rec["time"] = t
    recording = validate_recording(pd.DataFrame(rec), source=recording_id)
    annotation = _annotation(plan, performer, rng, recording_id)
    return recording, annotation


def _plan_notes(script: pd.DataFrame, perf: Performer, rng: np.random.Generator,
                force_factors: np.ndarray | None = None) -> pd.DataFrame:
    """True timing, bow directions and per-note magnitudes."""
    plan = script.reset_index(drop=True).copy()
    if "instrument" not in plan:
        plan["instrument"] = INSTRUMENT
    timing = _timing(plan, perf, rng)
    plan = plan.assign(**timing)
    plan = plan.assign(**phrase_positions(plan["run"].to_numpy()))
    plan = plan.assign(**_magnitudes(plan, perf, rng))
    factors = np.ones(4) if force_factors is None else np.asarray(force_factors, float)
    plan["force"] = plan["force"] * factors[plan["string"].to_numpy(int)]
    # true offsets: the next onset inside a run, the end of bow motion at a run's end
    plan["true_offset"] = np.where(plan["run_end"].to_numpy(), plan["stop"].to_numpy(),
                                   plan["nxt"].to_numpy())
    return plan


def _timing(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator) -> dict:
    """Onsets, durations, ends of bow motion and bow directions of every note."""
    cfg = simulator_config()["timing"]
    n = len(plan)
    tech = plan["technique"].to_numpy()
    dur = plan["duration"].to_numpy() * perf.tempo_scale
    on = np.empty(n)
    true_dur = dur * np.exp(rng.normal(0.0, perf.ioi_sd, n))
    true_dur = np.maximum(true_dur, cfg["min_duration_share"] * dur)
    rest = plan["rest_after"].to_numpy() * perf.tempo_scale
    tcur = cfg["start"]
    for i in range(n):
        on[i] = tcur
        tcur += true_dur[i] + rest[i] * float(np.exp(rng.normal(0, cfg["rest_sd"])))
    run = plan["run"].to_numpy()
    run_end = np.r_[run[1:] != run[:-1], True]
    nxt = np.r_[on[1:], np.inf]
    # end of bow motion of each note
    fill = np.clip(perf.staccato_fill * np.exp(rng.normal(0, cfg["fill_sd"], n)),
                   *cfg["fill_range"])
    stop = np.where(run_end, on + true_dur * rng.uniform(*cfg["run_end_fill"], n), nxt)
    stop = np.where(tech == "staccato", on + fill * true_dur, stop)
    stop = np.where(tech == "martele", on + np.clip(fill + cfg["martele_extra_fill"],
                                                    *cfg["martele_fill_range"]) * true_dur,
                    stop)
    stop = np.where((tech == "spiccato") & run_end, on + true_dur * cfg["spiccato_end_fill"],
                    stop)
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
    return dict(on=on, true_dur=true_dur, stop=stop, nxt=nxt, run_end=run_end,
                direction=direction, fill=fill, new_stroke=new_stroke)


def phrase_positions(run: np.ndarray) -> dict[str, np.ndarray]:
    """Position of each note in its run (phrase): ``phrase_pos`` in [0, 1], ``run_length``.

    Examples
    --------
    >>> out = phrase_positions(np.array([0, 0, 0, 1]))
    >>> out["phrase_pos"].tolist(), out["run_length"].tolist()
    ([0.0, 0.5, 1.0, 0.0], [3, 3, 3, 1])
    """
    run = np.asarray(run)
    starts = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    lengths = np.diff(np.r_[starts, run.size])
    length = np.repeat(lengths, lengths)
    index = np.arange(run.size) - np.repeat(starts, lengths)
    return dict(phrase_pos=np.where(length > 1, index / np.maximum(length - 1, 1), 0.0),
                run_length=length)


def _context_factor(plan: pd.DataFrame, perf: Performer) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and force factors of the context: phrase shape, accents, leaps and crossings.

    A run (phrase) swells by ``perf.crescendo`` from its first to its last note and arches
    by ``perf.phrase_arch`` (``sin(pi place) - 0.5``: fuller in the middle, lighter at the
    ends); the first note of a slur or a run is accented by ``perf.accent`` (force); the
    bow slows before a leap to the next note (``[magnitudes] leap_slowdown`` per octave)
    and lightens and slows on the note before a string crossing inside a run
    (``crossing_lift``, ``crossing_slow``: the arm prepares the new string's angle).
    """
    cfg = simulator_config()["magnitudes"]
    pos = plan["phrase_pos"].to_numpy()
    length = plan["run_length"].to_numpy()
    arch = np.where(length > 2, perf.phrase_arch * (np.sin(np.pi * pos) - 0.5), 0.0)
    swell = np.where(length > 1, 1.0 + perf.crescendo * (pos - 0.5), 1.0) * (1.0 + arch)
    starts = (plan["slur_position"].isin(["init"]) | plan["run_position"].isin(["init"]))
    accent = 1.0 + perf.accent * starts.to_numpy()
    pitch = plan["midi_pitch"].to_numpy(float)
    run = plan["run"].to_numpy()
    same_run = np.r_[run[1:] == run[:-1], False]
    leap = np.r_[np.abs(np.diff(pitch)), 0.0] * same_run
    slow = 1.0 - cfg["leap_slowdown"] * np.minimum(leap / 12.0, 1.0)
    string = plan["string"].to_numpy(int)
    crossing = np.r_[string[1:] != string[:-1], False] & same_run
    lift = 1.0 - cfg["crossing_lift"] * crossing
    slow = slow * (1.0 - cfg["crossing_slow"] * crossing)
    return swell * slow, swell * accent * lift


def _magnitudes(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator) -> dict:
    """Velocity, force, beta and bow-change acceleration of every note."""
    cfg = simulator_config()["magnitudes"]
    n = len(plan)
    tech = plan["technique"].to_numpy()
    true_dur = plan["true_dur"].to_numpy()
    fill = plan["fill"].to_numpy()
    v, f, b = dynamics_table("violinist").at(plan["dynamic"].to_numpy())
    var = perf.variability
    length_factor = np.clip((cfg["length_reference"] / true_dur) ** cfg["length_exponent"],
                            *cfg["length_factor_range"])
    tech_v = pd.Series(tech).map(cfg["technique_velocity"]).to_numpy()
    vel = v * perf.velocity_scale * length_factor * tech_v * np.exp(rng.normal(0, var, n))
    # a staccato / spiccato burst cannot exceed the acceleration the arm can give
    burst = np.where(tech == "staccato", fill * true_dur, true_dur)
    limit = np.where(np.isin(tech, ("staccato", "spiccato")),
                     cfg["burst_acceleration"] * burst / np.pi, np.inf)
    ctx_v, ctx_f = _context_factor(plan, perf)
    vel = np.minimum(vel * ctx_v, limit)
    fr = plan["finger_ratio"].to_numpy()
    force = f * perf.force_scale * ctx_f * np.exp(rng.normal(0, var, n))
    slur = plan["slur_position"].to_numpy()
    lean = cfg["slur_force"]
    force *= np.where(slur == "init", lean["init"], np.where(slur == "end", lean["end"], 1.0))
    # a slower bow plays closer to the bridge at the same dynamic (Schoonderwaldt 2009)
    contact = length_factor ** cfg["beta_speed_exponent"]
    beta = (b * perf.beta_scale * contact * np.exp(rng.normal(0, var, n))
            / np.sqrt(1.0 - fr))
    accel = np.clip(perf.accel * np.exp(rng.normal(0, cfg["accel_sd"], n)), *cfg["accel_range"])
    accel = np.where(tech == "martele",
                     np.clip(perf.martele_accel * np.exp(rng.normal(0, cfg["martele_accel_sd"],
                                                                    n)),
                             *cfg["martele_accel_range"]),
                     accel)
    tilt = np.where(plan["run_length"].to_numpy() > 1,
                    perf.crescendo / np.maximum(plan["run_length"].to_numpy() - 1, 1), 0.0)
    return dict(vel=vel, force=force, beta=np.clip(beta, *cfg["beta_range"]), accel=accel,
                tilt=tilt)


def _slicer(t: np.ndarray) -> Slicer:
    """``sl(a, b)``: the frames of ``t`` (a uniform grid from 0) in [a, b)."""
    fs = 1.0 / (t[1] - t[0])
    n_frames = t.size

    def sl(a: float, b: float) -> slice:
        return slice(max(int(np.ceil(a * fs)), 0), min(int(np.ceil(b * fs)), n_frames))

    return sl


def _render(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator,
            t: np.ndarray) -> dict[str, np.ndarray]:
    """Noise-free signals on the frame grid ``t``."""
    fs = 1.0 / (t[1] - t[0])
    sl = _slicer(t)
    v = np.zeros(t.size)
    force = np.zeros(t.size)
    tech = plan["technique"].to_numpy()
    run = plan["run"].to_numpy()
    n = len(plan)
    # ---- velocity and force, stroke by stroke
    i = 0
    while i < n:
        j = i + 1  # one stroke: a legato slur, otherwise one note
        if tech[i] == "legato":
            while j < n and run[j] == run[i] and not plan["new_stroke"].iloc[j]:
                j += 1
        stroke(plan, i, j, t, v, force, sl, rng, perf)
        i = j
    pos = _plan_bow(plan, v, force, sl, fs)
    semis, string, beta, cents = _left_hand(plan, perf, rng, t, sl)
    lh = simulator_config()["left_hand"]
    return dict(bow_velocity=v, bow_force=force, beta=np.clip(beta, *lh["beta_range"]),
                bow_position=pos, string=string,
                finger_ratio=finger_ratio(np.maximum(semis + cents / 100.0, 0.0)),
                pitch_deviation_cents=cents)


def _plan_bow(plan: pd.DataFrame, v: np.ndarray, force: np.ndarray, sl: Slicer,
              fs: float) -> np.ndarray:
    """Bow position per frame: per run, fit the travel inside the hair; retakes in the rests.

    Scales ``v`` and raises ``force`` in place where a run had to be slowed down to fit, and
    adds the retake's motion to ``v`` where the lifted bow travels far.
    """
    cfg = simulator_config()["bow"]
    budget = BowBudget(instrument_facts(str(plan["instrument"].iloc[0])).bow_length)
    on = plan["on"].to_numpy()
    stop = plan["stop"].to_numpy()
    run = plan["run"].to_numpy()
    n = len(plan)
    pos = np.zeros(v.size)
    runs = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    prev_end_pos = cfg["rest_position"]
    prev_stop_frame = 0
    for k, first in enumerate(runs):
        last = (runs[k + 1] if k + 1 < len(runs) else n) - 1
        s = sl(on[first] - cfg["run_lead"], stop[last] + cfg["run_tail"])
        fit = budget.fit(budget.travel(np.cumsum(v[s]) / fs))
        if fit.scale < 1.0:
            v[s] *= fit.scale
            force[s] *= 1.0 + cfg["squeeze_force"] * (1 - fit.scale)
        travel = fit.travel
        want = cfg["down_start"] if plan["direction"].iloc[first] > 0 else cfg["up_start"]
        lo, hi = fit.start_window
        start = float(np.clip(want - travel[0], lo, hi))
        # a retake in a short rest can only move the lifted bow so far
        reach = float(budget.travel(cfg["retake_speed"] * max(s.start - prev_stop_frame, 0)
                                    / fs / (0.5 * np.pi)))
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
            if abs(delta) > cfg["retake_min"] and a > 0:
                # a start window that leaves the retake out of reach cannot make the lifted
                # bow faster than an arm moves it (its trace is capped, the plan is kept)
                lifted = np.gradient(pos[a:b]) * fs * budget.bow_length
                v[a:b] += np.clip(lifted, -cfg["retake_max_speed"], cfg["retake_max_speed"])
        prev_end_pos = pos[s.stop - 1]
        prev_stop_frame = s.stop
    pos[prev_stop_frame:] = prev_end_pos
    return pos


def _semitones(plan: pd.DataFrame) -> np.ndarray:
    """Semitones of each planned note above its open string (0 = open string)."""
    opens = np.asarray(instrument_facts(str(plan["instrument"].iloc[0])).open_strings)
    return (plan["midi_pitch"].to_numpy() - opens[plan["string"]]).astype(np.float64)


def _left_hand(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator, t: np.ndarray,
               sl: Slicer) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nominal semitones, string, beta and the left hand's cents per frame.

    Finger and string change slightly before the bow (legato: at the onset); beta glides to
    each note's value with a slow drift; the cents (intonation, vibrato, shifts) are
    :func:`gesture_db.playing_left_hand.left_hand_contour`'s from the plan's ``lh_*``
    columns.
    """
    cfg = simulator_config()["left_hand"]
    tech = plan["technique"].to_numpy()
    n = len(plan)
    on = plan["on"].to_numpy()
    semitone = _semitones(plan)
    phases = np.zeros(n)
    semis = np.zeros(t.size)
    string = np.full(t.size, int(plan["string"].iloc[0]), dtype=np.int8)
    beta = np.full(t.size, float(plan["beta"].iloc[0]))
    lead = np.where(tech == "legato", 0.0,
                    np.clip(rng.normal(perf.finger_lead, cfg["lead_sd"], n), 0.0,
                            cfg["lead_max"]))
    lead = np.where(plan["run_position"].isin(["init", "iso"]).to_numpy(),
                    rng.uniform(*cfg["run_lead"], n), lead)
    change = on - lead
    for i in range(n):
        end = change[i + 1] if i + 1 < n else t[-1] + 1
        s = sl(change[i], end)
        semis[s] = semitone[i]
        string[s] = plan["string"].iloc[i]
        if plan["true_dur"].iloc[i] > cfg["vibrato_min_duration"] and \
                tech[i] in ("detache", "legato"):
            phases[i] = rng.uniform(0, 2 * np.pi)
        tt = t[s] - change[i]
        target = plan["beta"].iloc[i] * (1 + cfg["beta_drift"] * rng.normal() * tt)
        start_beta = beta[s.start - 1] if s.start > 0 else target
        w = np.clip(tt / cfg["beta_glide"], 0.0, 1.0)
        beta[s] = start_beta + (target - start_beta) * w
    cents = left_hand_contour(plan, {k: plan[f"lh_{k}"].to_numpy() for k in
                                     ("intonation", "rate", "extent", "delay", "glide")},
                              semitone, t, change, phases)
    return semis, string, beta, cents


def _add_noise(sig: dict[str, np.ndarray], rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Sensor noise of a motion-capture and strain-gauge setup."""
    cfg = simulator_config()["noise"]
    n = sig["bow_velocity"].size
    out = dict(sig)
    out["bow_velocity"] = sig["bow_velocity"] + rng.normal(0, cfg["bow_velocity"], n)
    out["bow_force"] = np.minimum(np.abs(sig["bow_force"] + rng.normal(0, cfg["bow_force"], n)),
                                  RECORDING.column("bow_force").maximum)
    out["beta"] = np.clip(sig["beta"] + rng.normal(0, cfg["beta"], n), *cfg["beta_range"])
    out["bow_position"] = np.clip(sig["bow_position"] + rng.normal(0, cfg["bow_position"], n),
                                  0.0, 1.0)
    out["finger_ratio"] = np.clip(sig["finger_ratio"] + rng.normal(0, cfg["finger_ratio"], n),
                                  0.0, limits().max_finger_ratio)
    return out


def _annotation(plan: pd.DataFrame, perf: Performer, rng: np.random.Generator,
                recording_id: str) -> pd.DataFrame:
    cfg = simulator_config()["alignment"]
    n = len(plan)
    # coarse-alignment error: slowly varying (sd ~30 ms) plus per-note jitter (sd 10 ms)
    drift = np.zeros(n)
    for i in range(1, n):
        drift[i] = cfg["drift_decay"] * drift[i - 1] + rng.normal(0, cfg["drift_sd"])
    err = drift + rng.normal(0, cfg["jitter_sd"], n)
    onset = np.maximum(plan["on"].to_numpy() + err, 0.0)
    onset = np.maximum.accumulate(onset)
    offset = np.maximum(plan["true_offset"].to_numpy() + np.r_[err[1:], err[-1]],
                        onset + cfg["min_length"])
    frame = pd.DataFrame(dict(
        recording_id=recording_id, note_index=np.arange(n, dtype=np.int32), onset=onset,
        offset=offset, midi_pitch=plan["midi_pitch"], string=plan["string"],
        finger_ratio=plan["finger_ratio"], dynamic=plan["dynamic"],
        technique=plan["technique"],
        bow_direction=np.where(plan["direction"] > 0, "down", "up"),
        slur_position=plan["slur_position"], run_position=plan["run_position"],
        tempo_bpm=plan["tempo_bpm"], performer=perf.name,
        true_onset=plan["on"], true_offset=plan["true_offset"],
        true_intonation_cents=plan["lh_intonation"], true_vibrato_rate_hz=plan["lh_rate"],
        true_vibrato_extent_cents=plan["lh_extent"]))
    return validate_annotation(frame, source=recording_id)


__all__ = ["play_script"]
