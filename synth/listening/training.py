"""Training of one string x dynamic pair (``feedback-control.md``, Vivi 2011 section 5).

1. :func:`basic_training`: at fingers 0, 4 and 7 semitones, start at 1 N and double until a
   clip is judged 5, go back to 0.5 N and halve until one is judged 1, then fill gaps between
   judged forces until every class has an example (and a few clips cover the class-3 band),
   then add clips on a log grid (``grid_step`` octaves) between the lowest and highest judged
   force. All clips are played on one violin body (``body_seed``); the automatic teacher
   also judges each recorded hop (``hop_window`` hops of sound ending with it).
2. :func:`fit_from_clips`: features of every recorded hop, labelled with the teacher's class
   of that hop (its clip's class for other judges), train the pair's scaler + SVC (10-fold
   CV by clip in the metadata: a clip's hops stay in one fold).
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

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from synth.engines import get_engine
from synth.listening.classifier import FINGERS, PairModel, fit_pair
from synth.listening.clips import (
    MAX_ACCELERATION,
    Clip,
    ClipSpec,
    auto_hop_labels,
    auto_label,
    recorded_frame_ends,
    render_clip,
)
from synth.listening.controller import ControllerSettings, HopPlan, PerformanceLog, perform
from synth.listening.features import HOP, WINDOW, batch_features, yin_window_for

#: Vivi's bow lanes: dynamic -> (bow velocity m/s, beta).
DEFAULT_LANES = {"p": (0.20, 0.14), "mp": (0.26, 0.12), "mf": (0.33, 0.10), "f": (0.40, 0.08)}

Teacher = Callable[[Clip], int]


@dataclass(frozen=True)
class TrainingSettings:
    """Sizes of the training searches (defaults: the full training; tests use fewer)."""

    settle: float = 0.7
    record: float = 0.3
    fingers: tuple[float, ...] = FINGERS
    start_force: float = 1.0
    min_force: float = 0.002
    max_force: float = 50.0
    band_clips: int = 2
    grid_step: float = 0.125
    body_seed: int = 0
    hop_window: int = 8
    k_candidates: tuple[float, ...] = (1.005, 1.01, 1.02, 1.035, 1.05, 1.1)
    k_repeats: int = 3
    k_note: float = 0.6
    f_candidates: int = 6
    f_rounds: int = 2
    f_repeats: int = 2
    f_note: float = 0.45
    controller: ControllerSettings = field(default_factory=ControllerSettings)


QUICK = TrainingSettings(settle=0.6, record=0.3, band_clips=1,
                         k_candidates=(1.005, 1.01, 1.02, 1.05), k_repeats=1, k_note=0.6,
                         f_candidates=5, f_rounds=1, f_repeats=1, f_note=0.6)


@dataclass
class JudgedClip:
    """A clip with its class.

    ``hop_labels``, when known, is the teacher's class of each recorded frame
    (:func:`synth.listening.clips.auto_hop_labels`); the classifier learns those instead of
    ``label`` for every frame. A judge who changes ``label`` must clear them.
    """

    clip: Clip
    label: int
    hop_labels: np.ndarray | None = None

    @property
    def force(self) -> float:
        """Bow force of the clip, N."""
        return self.clip.spec.bow_force


def _play(spec: ClipSpec, settings: TrainingSettings, seed: int, teacher: Teacher) -> JudgedClip:
    sr = 44100
    context = yin_window_for(spec.nominal_frequency(), sr) / sr
    clip = render_clip(spec, settle=settings.settle, record=settings.record, seed=seed,
                       context=context, body_seed=settings.body_seed)
    hops = auto_hop_labels(clip, window_hops=settings.hop_window) if (
        teacher is auto_label and settings.hop_window > 0) else None
    return JudgedClip(clip, int(teacher(clip)), hops)


def basic_training(instrument: str, string: int, dynamic: str, *,
                   lane: tuple[float, float] | None = None,
                   settings: TrainingSettings | None = None, teacher: Teacher = auto_label,
                   seed: int = 0) -> list[JudgedClip]:
    """Judge steady clips of one pair at fingers 0, 4 and 7 semitones.

    Parameters
    ----------
    instrument : str
    string : int
    dynamic : str
        Lane name (``p``, ``mp``, ``mf``, ``f``).
    lane : (float, float), optional
        Bow velocity (m/s) and beta of the lane (default :data:`DEFAULT_LANES`).
    settings : TrainingSettings, optional
    teacher : callable
        ``teacher(clip) -> class 1..5`` (default: the automatic teacher).
    seed : int

    Returns
    -------
    list of JudgedClip
    """
    settings = settings or TrainingSettings()
    v, beta = lane or DEFAULT_LANES[dynamic]
    out: list[JudgedClip] = []
    for i, semis in enumerate(settings.fingers):
        judged: list[JudgedClip] = []

        def play(force: float, semis: float = semis, i: int = i,
                 judged: list[JudgedClip] = judged) -> int:
            spec = ClipSpec(instrument, string, semis, float(force), v, beta)
            j = _play(spec, settings, seed * 100000 + i * 1000 + len(judged), teacher)
            judged.append(j)
            return j.label

        force = settings.start_force
        while force <= settings.max_force and play(force) < 5:
            force *= 2.0
        force = settings.start_force / 2.0
        while force >= settings.min_force and play(force) > 1:
            force /= 2.0
        for _ in range(12):  # gap filling: a force between the neighbours of a missing class
            gap = _missing_gap(judged)
            if gap is None:
                break
            play(gap)
        for _ in range(settings.band_clips):
            band = _band_force(judged)
            if band is not None:
                play(band)
        for f in _grid_forces(judged, settings.grid_step, settings.start_force):
            play(f)
        _relabel_force_side(judged)
        out.extend(judged)
    return out


def _missing_gap(judged: list[JudgedClip]) -> float | None:
    """Geometric midpoint between the clips around the first missing class, if any."""
    order = sorted(judged, key=lambda j: j.force)
    have = {j.label for j in order}
    for c in range(2, 5):
        if c in have:
            continue
        below = [j.force for j in order if j.label < c]
        above = [j.force for j in order if j.label > c]
        if not below or not above:
            continue
        lo, hi = max(below), min(f for f in above if f > max(below)) if any(
            f > max(below) for f in above) else (None, None)
        if lo is None or hi / lo < 1.02:
            continue
        return float(np.sqrt(lo * hi))
    return None


def _grid_forces(judged: list[JudgedClip], step: float, anchor: float) -> list[float]:
    """Forces (N) of a log grid between the lowest and highest judged force.

    The grid has ``step`` octaves between forces and passes through ``anchor``; forces within
    a third of a step of a judged force are left out.
    """
    if step <= 0 or len(judged) < 2:
        return []
    have = np.log2([j.force for j in judged])
    lo, hi = have.min(), have.max()
    base = np.log2(anchor)
    ks = np.arange(np.ceil((lo - base) / step), np.floor((hi - base) / step) + 1)
    grid = base + ks * step
    far = np.min(np.abs(grid[:, None] - have[None, :]), axis=1) > step / 3.0
    return [float(2.0**g) for g in grid[far]]


def _band_force(judged: list[JudgedClip]) -> float | None:
    """A force inside the widest gap next to a class-3 clip (more examples near the band)."""
    order = sorted(judged, key=lambda j: j.force)
    best, width = None, 1.02
    for a, b in zip(order[:-1], order[1:], strict=True):
        if 3 in (a.label, b.label) and b.force / a.force > width:
            best, width = float(np.sqrt(a.force * b.force)), b.force / a.force
    return best


def _relabel_force_side(judged: list[JudgedClip]) -> None:
    """Judge in context: 'too little' above the acceptable band means too much, and back.

    The teacher's 2 (multiple slipping) heard at a force above the centre of the class-3
    clips is relabelled 4, and a 4 below it 2 (a human judging a force sweep hears which side
    of the good sound a clip lies on). Hop labels follow the same rule.
    """
    good = [j.force for j in judged if j.label == 3]
    if not good:
        return
    centre = float(np.exp(np.mean(np.log(good))))
    for j in judged:
        if j.label == 2 and j.force > centre:
            j.label = 4
        elif j.label == 4 and j.force < centre:
            j.label = 2
        if j.hop_labels is not None:
            h = j.hop_labels
            j.hop_labels = np.where((h == 2) & (j.force > centre), 4,
                                    np.where((h == 4) & (j.force < centre), 2, h))


def clip_features(clips: list[JudgedClip], *,
                  sample_rate: int = 44100) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Hop features of the recorded parts of judged clips.

    Returns
    -------
    features : np.ndarray [shape=(n_hops, n_features)]
    labels : np.ndarray [shape=(n_hops,)]
        The clip's hop labels where it has them, else its label on every hop.
    clip_index : np.ndarray [shape=(n_hops,)]
    """
    feats, labels, index = [], [], []
    for i, j in enumerate(clips):
        f0 = j.clip.spec.nominal_frequency()
        yw = yin_window_for(f0, sample_rate)
        f = batch_features(j.clip.audio, f0, sample_rate=sample_rate, yin_window=yw)
        ends = recorded_frame_ends(j.clip)
        f = f[(ends - WINDOW) // HOP]
        feats.append(f)
        hops = j.hop_labels
        labels.append(hops if hops is not None and hops.size == f.shape[0]
                      else np.full(f.shape[0], j.label))
        index.append(np.full(f.shape[0], i))
    return np.vstack(feats), np.concatenate(labels), np.concatenate(index)


def fit_from_clips(clips: list[JudgedClip], *, instrument: str, string: int, dynamic: str,
                   lane: tuple[float, float] | None = None, seed: int = 0) -> PairModel:
    """Train the pair's classifier on the hops of judged clips; store lane and force range."""
    X, y, index = clip_features(clips)
    model = fit_pair(X, y, instrument=instrument, string=string, dynamic=dynamic, seed=seed,
                     groups=index)
    n_hop_labelled = sum(j.hop_labels is not None for j in clips)
    model.metadata["labels"] = (f"per hop (teacher, {n_hop_labelled} of {len(clips)} clips)"
                                if n_hop_labelled else "per clip")
    v, beta = lane or DEFAULT_LANES[dynamic]
    audible = [j.force for j in clips if j.label >= 2] or [j.force for j in clips]
    model.metadata.update(
        n_clips=len(clips), velocity=v, beta=beta,
        force_range=[float(min(audible)), float(max(j.force for j in clips))])
    good = [j.force for j in clips if j.label == 3]
    if good:
        model.metadata["good_range"] = [float(min(good)), float(max(good))]
    model.metadata["good_by_finger"] = good_bands(clips)
    return model


def good_bands(clips: list[JudgedClip]) -> dict[str, list[float]]:
    """Per finger position, the lowest and highest force judged 3 (N).

    Returns
    -------
    dict of str to [float, float]
        Keyed by the finger in semitones (``"0"``, ``"4"``, ``"7"``); fingers without a
        class-3 clip are left out.
    """
    out: dict[str, list[float]] = {}
    for semis in sorted({j.clip.spec.semitones for j in clips}):
        good = [j.force for j in clips if j.clip.spec.semitones == semis and j.label == 3]
        if good:
            out[f"{semis:g}"] = [float(min(good)), float(max(good))]
    return out


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
    log = perform(plan, {(model.string, model.dynamic): model}, inst,
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
    stats = hop_statistics(onsets, period, audio, f0=np.full(onsets.size, f0),
                           sample_rate=44100, reference_rms=reference_rms(model.instrument))
    speed = np.abs(plan.velocity[:, s])
    sustained = np.flatnonzero(speed >= 0.9 * speed.max())
    string_ref = load_instrument(model.instrument).strings[s].reference_force
    beta = float(plan.beta[0, s])
    return np.array([judge(stats[k], force_ratio=log.force[k, s] / reference_force(
        string_ref, max(speed[k], 1e-3), beta)) for k in sustained], np.int64)


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
