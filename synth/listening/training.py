"""Training of one string x dynamic pair (``feedback-control.md``, Vivi 2011 section 5).

1. :func:`synth.listening.basic_training.basic_training`: judged steady clips at fingers 0,
   4 and 7 semitones over the pair's force range.
2. :func:`synth.listening.basic_training.fit_from_clips`: the pair's scaler + SVC on the
   clips' hop features (10-fold CV by clip in the metadata).
3. :func:`search_initial_force` (first, with the smallest K): per finger, practice notes start
   at forces log-spaced over that finger's class-3 band; the teacher judges every sustained
   hop and the cost is sum (3 - c)^2 (the attack's cost plus later errors); median over
   repeats, zoomed in around the best; ties go to the band's centre.
4. :func:`search_k`: the pattern (three fingers, starts at half, once and twice the initial
   force) under feedback with each candidate K, judged by the teacher; note cost =
   product over runs of same-sign error of (1 + sum (3 - c)^2) (the paper's eq. 7; the 1 +
   keeps a perfect run from zeroing the product); inter-quartile geometric mean over
   repeats; lowest cost wins. The teacher judging practice notes stands in for the human of
   the paper's practice step; the controller itself stays black-box when it plays.

Everything is deterministic given ``seed``.
"""

from __future__ import annotations

import numpy as np

from synth.engines import get_engine
from synth.listening.basic_training import (
    JudgedClip,
    basic_training,
    clip_features,
    fit_from_clips,
    good_bands,
)
from synth.listening.classifier import FINGERS, PairModel
from synth.listening.clips import MAX_ACCELERATION, auto_label
from synth.listening.controller import HopPlan, PerformanceLog, play_plan
from synth.listening.features import HOP
from synth.listening.training_settings import DEFAULT_LANES, QUICK, Teacher, TrainingSettings

__all__ = ["DEFAULT_LANES", "QUICK", "JudgedClip", "Teacher", "TrainingSettings",
           "attack_cost", "basic_training", "clip_features", "fit_from_clips", "good_bands",
           "note_plan", "search_initial_force", "search_k", "stability_cost",
           "teacher_note_classes", "train_pair"]


def note_plan(semitones: float, f0: float, *, velocity: float, beta: float, duration: float,
              dynamic: str, string: int, n_strings: int = 4,
              sample_rate: int = 44100) -> HopPlan:
    """A single sustained note: the bow accelerates at 5 m/s^2 and holds (training pattern)."""
    n = max(int(round(duration * sample_rate / HOP)), 2)
    t = (np.arange(n) + 1) * HOP / sample_rate
    speed = np.minimum(t * MAX_ACCELERATION, velocity)
    shape = (n, n_strings)
    plan = HopPlan(
        bowed=np.zeros(shape, bool), velocity=np.zeros(shape), beta=np.full(shape, beta),
        semitones=np.zeros(shape), expected_f0=np.full(shape, f0),
        target_speed=np.full(shape, velocity), dynamic=np.full(shape, dynamic, object),
        note_start=np.zeros(shape, bool), finger_change=np.zeros(shape, bool))
    plan.bowed[:, string] = True
    plan.velocity[:, string] = speed
    plan.semitones[:, string] = semitones
    plan.note_start[0, string] = True
    return plan


def _play_note(model: PairModel, semitones: float, *, force: float, K: float,
               duration: float, settings: TrainingSettings, seed: int,
               record_diagnostics: bool = False) -> tuple[HopPlan, PerformanceLog, float]:
    """Play one training note under feedback; return the plan, the log and its f0 (Hz)."""
    from synth.strings import load_instrument

    inst_c = load_instrument(model.instrument)
    f0 = inst_c.strings[model.string].nominal_frequency(inst_c.tuning_a4) * 2 ** (semitones / 12)
    v = float(model.metadata.get("velocity", DEFAULT_LANES[model.dynamic][0]))
    beta = float(model.metadata.get("beta", DEFAULT_LANES[model.dynamic][1]))
    plan = note_plan(semitones, f0, velocity=v, beta=beta, duration=duration,
                     dynamic=model.dynamic, string=model.string,
                     n_strings=len(inst_c.strings))
    # Practice notes are played on the clips' violin (the training body), noise seeded anew.
    inst = get_engine("modal", model.instrument, seed=seed, body_seed=settings.body_seed)
    log = play_plan(plan, {(model.string, model.dynamic): model}, inst,
                    rng=np.random.default_rng(seed), settings=settings.controller, K=K,
                    initial_force=force, record_diagnostics=record_diagnostics)
    return plan, log, f0


def _note_classes(model: PairModel, semitones: float, *, force: float, K: float,
                  duration: float, settings: TrainingSettings, seed: int) -> np.ndarray:
    """Classes the controller heard during one training note (classified hops only)."""
    _, log, _ = _play_note(model, semitones, force=force, K=K, duration=duration,
                           settings=settings, seed=seed)
    c = log.classes[:, model.string]
    return c[c > 0]


def teacher_note_classes(model: PairModel, semitones: float, *, force: float, K: float,
                         duration: float, settings: TrainingSettings,
                         seed: int) -> np.ndarray:
    """The automatic teacher's class of every sustained hop of one training note.

    The teacher listens to the practice note (as the evaluation does: slip onsets and
    periodicity per hop); hops count once the bow has reached 90 % of its speed.

    Returns
    -------
    np.ndarray [shape=(n_sustained,)], int
    """
    from synth.listening.clips import reference_rms
    from synth.listening.teacher import hop_statistics, judge, reference_force
    from synth.strings import load_instrument

    plan, log, f0 = _play_note(model, semitones, force=force, K=K, duration=duration,
                               settings=settings, seed=seed, record_diagnostics=True)
    s = model.string
    hops = log.diagnostics[s]
    onsets = np.array([d.slip_onsets for _, d in hops], np.float64)
    period = np.array([d.sounding_period for _, d in hops], np.float64)
    audio = np.concatenate([log.audio, np.zeros(4 * HOP, np.float32)]).astype(np.float64)
    times = np.concatenate([d.onset_times for _, d in hops]) if hops else np.zeros(0)
    stats = hop_statistics(onsets, period, audio, f0=np.full(onsets.size, f0),
                           sample_rate=44100, reference_rms=reference_rms(model.instrument),
                           onset_times=times, start_time=hops[0][0] * HOP / 44100 if hops
                           else 0.0)
    speed = np.abs(plan.velocity[:, s])
    sustained = np.flatnonzero(speed >= 0.9 * speed.max())
    string_ref = load_instrument(model.instrument).strings[s].reference_force
    beta = float(plan.beta[0, s])
    return np.array([judge(stats[k], force_ratio=log.force[k, s] / reference_force(
        string_ref, max(speed[k], 1e-3), beta), thresholds=settings.thresholds)
        for k in sustained], np.int64)


def stability_cost(classes: np.ndarray) -> float:
    """Eq. 7 with 1 + per run: product over same-sign runs of (1 + sum (3 - c)^2)."""
    cost = 1.0
    run, sign = 0.0, 0
    for c in classes:
        s = int(np.sign(3 - c))
        if s and sign and s != sign:
            cost *= 1.0 + run
            run = 0.0
        if s:
            sign = s
        run += (3.0 - c) ** 2
    return cost * (1.0 + run)


def attack_cost(classes: np.ndarray, *, window: int = 9, threshold: float = 0.5) -> float:
    """Eq. 8-9: sum (3 - c)^2 until the mean over the last ``window`` hops < ``threshold``."""
    err = (3.0 - np.asarray(classes, np.float64)) ** 2
    for k in range(window, err.size + 1):
        if err[k - window:k].mean() < threshold:
            return float(err[:k].sum())
    return float(err.sum())


def _iq_geomean(costs: list[float]) -> float:
    logs = np.sort(np.log(np.maximum(np.asarray(costs, np.float64), 1e-9)))
    q = logs.size // 4
    mid = logs[q:logs.size - q] if logs.size - 2 * q > 0 else logs
    return float(np.exp(mid.mean()))


def search_k(model: PairModel, *, settings: TrainingSettings | None = None,
             seed: int = 0) -> tuple[float, dict[float, float]]:
    """Choose K for a pair: the factor under which practice notes sound best to the teacher.

    The training pattern plays each finger position starting at half, once and twice the
    learned initial force (or, before it is learned, the quarter, centre and top of the
    class-3 band) under feedback with each candidate K. The teacher judges every sustained
    hop; a note's cost is eq. 7 on those classes (product over same-sign runs of
    1 + sum (3 - c)^2); a repeat's cost is the product over its notes; the inter-quartile
    geometric mean over repeats is kept and the lowest-cost K wins (ties: the smaller K).

    Returns
    -------
    K : float
    costs : dict of float to float
        Cost per candidate K.
    """
    settings = settings or TrainingSettings()
    costs = {}
    for K in settings.k_candidates:
        per_repeat = []
        for r in range(settings.k_repeats):
            log_cost = 0.0
            for i, semis in enumerate(settings.fingers):
                for j, f in enumerate(_pattern_starts(model, semis)):
                    c = teacher_note_classes(model, semis, force=f, K=K,
                                             duration=settings.k_note, settings=settings,
                                             seed=seed + 97 * r + 11 * i + j)
                    log_cost += np.log(stability_cost(c))
            per_repeat.append(float(np.exp(log_cost)))
        costs[float(K)] = _iq_geomean(per_repeat)
    best = min(costs, key=lambda k: (costs[k], k))
    return best, costs


def _pattern_starts(model: PairModel, semitones: float) -> tuple[float, float, float]:
    """Starting forces (N) of the K pattern at a finger position."""
    if model.metadata.get("initial_forces"):
        f = model.initial_force(semitones)
    else:
        lo, hi = _search_band(model, semitones)
        f = float(np.sqrt(lo * hi))
    return f / 2.0, f, 2.0 * f


def search_initial_force(model: PairModel, semitones: float, *,
                         settings: TrainingSettings | None = None, seed: int = 0) -> float:
    """Choose the initial force (N) of a pair at one finger position.

    Practice notes start at forces log-spaced over the finger's class-3 band of the basic
    training (the whole audible range when it has none); the teacher judges every sustained
    hop and a note's cost is sum (3 - c)^2 over them (the attack's cost, eq. 8, plus any later
    error); the median over ``f_repeats`` seeds is kept. The search zooms in around the best
    force ``f_rounds`` times; ties go to the force nearest the band's geometric centre.
    """
    settings = settings or TrainingSettings()
    lo, hi = _search_band(model, semitones)
    centre = float(np.sqrt(lo * hi))
    tried: dict[float, float] = {}
    for _ in range(max(settings.f_rounds, 1)):
        for f in np.geomspace(lo, hi, settings.f_candidates):
            key = float(f)
            if key in tried:
                continue
            costs = [float(np.sum((3.0 - teacher_note_classes(
                model, semitones, force=key, K=model.K, duration=settings.f_note,
                settings=settings, seed=seed + 31 * r)) ** 2))
                for r in range(settings.f_repeats)]
            tried[key] = float(np.median(costs))
        order = sorted(tried)
        best = min(order, key=lambda f: (tried[f], abs(np.log(f / centre))))
        k = order.index(best)
        lo, hi = order[max(k - 1, 0)], order[min(k + 1, len(order) - 1)]
        if hi / lo < 1.05:
            break
    return float(min(tried, key=lambda f: (tried[f], abs(np.log(f / centre)))))


def _search_band(model: PairModel, semitones: float) -> tuple[float, float]:
    """Forces (N) the initial-force search covers at a finger position."""
    band = model.metadata.get("good_by_finger", {}).get(f"{semitones:g}")
    if band is None:
        band = model.metadata.get("good_range") or model.metadata["force_range"]
    lo, hi = (float(x) for x in band)
    if hi / lo < 1.5:  # a single judged force: search around it
        lo, hi = lo / 1.4, hi * 1.4
    return lo, hi


def train_pair(instrument: str, string: int, dynamic: str, *,
               lane: tuple[float, float] | None = None,
               settings: TrainingSettings | None = None, teacher: Teacher = auto_label,
               clips: list[JudgedClip] | None = None, seed: int = 0) -> tuple[PairModel,
                                                                           list[JudgedClip]]:
    """Basic training (unless ``clips`` are given), classifier, K and initial forces.

    Returns
    -------
    model : PairModel
        With ``K``, ``k_costs``, ``initial_forces`` in its metadata.
    clips : list of JudgedClip
    """
    settings = settings or TrainingSettings()
    if clips is None:
        clips = basic_training(instrument, string, dynamic, lane=lane, settings=settings,
                               teacher=teacher, seed=seed)
    model = fit_from_clips(clips, instrument=instrument, string=string, dynamic=dynamic,
                           lane=lane, seed=seed)
    model.metadata.update(K=settings.k_candidates[0])
    forces = [search_initial_force(model, semis, settings=settings, seed=seed + 7 * i)
              for i, semis in enumerate(FINGERS)]
    model.metadata.update(initial_forces=forces)
    K, costs = search_k(model, settings=settings, seed=seed)
    model.metadata.update(K=K, k_costs={str(k): v for k, v in costs.items()})
    return model, clips
