"""Basic training of one string x dynamic pair: judged clips and the pair's classifier.

1. :func:`basic_training`: at fingers 0, 4 and 7 semitones, start at 1 N and double until a
   clip is judged 5, go back to 0.5 N and halve until one is judged 1, then fill gaps between
   judged forces until every class has an example (and a few clips cover the class-3 band),
   then add clips on a log grid (``grid_step`` octaves) between the lowest and highest judged
   force. All clips are played on one violin body (``body_seed``); the automatic teacher
   also judges each recorded hop (``hop_window`` hops of sound ending with it).
2. :func:`fit_from_clips`: features of every recorded hop, labelled with the teacher's class
   of that hop (its clip's class for other judges), train the pair's scaler + SVC (10-fold
   CV by clip in the metadata: a clip's hops stay in one fold).

The K and initial-force searches that follow are in :mod:`synth.listening.training`.
Everything is deterministic given ``seed``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from synth.listening.classifier import PairModel, fit_pair
from synth.listening.clips import (
    Clip,
    ClipSpec,
    auto_hop_labels,
    auto_label,
    recorded_frame_ends,
    render_clip,
)
from synth.listening.features import HOP, WINDOW, batch_features, yin_window_for
from synth.listening.training_settings import DEFAULT_LANES, Teacher, TrainingSettings


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
    automatic = teacher is auto_label
    hops = auto_hop_labels(clip, window_hops=settings.hop_window,
                           thresholds=settings.thresholds) if (
        automatic and settings.hop_window > 0) else None
    label = auto_label(clip, thresholds=settings.thresholds) if automatic else teacher(clip)
    return JudgedClip(clip, int(label), hops)


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
