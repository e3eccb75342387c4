"""Judge gesture samples by playing them: the teacher's class histogram from practice renders.

Each chosen sample is played alone (its own duration, pitch, string and dynamic, a rest
between samples) through the modal engine on its instrument, with the forces adapted to the
model's strings and brought into the playable space as sampling does
(:func:`pipelines.methods.sampling_db.adapt_forces`, the contact point's range, the force
band and the bite); the yardstick (:func:`pipelines.listening.evaluate.evaluate`, slip
record) gives every sustained hop the automatic teacher's class. The histograms go to the database's
:data:`data_schemas.gesture_db.DB_QUALITY` table; the search then adds each sample's quality
cost (:func:`gesture_db.search.quality_costs`, weight ``[weights] quality``).
"""

from __future__ import annotations

import os

import numpy as np
import pandas as pd

from data_schemas.errors import ParameterError

#: Rest between two practice samples (s): each is played as a note of its own.
GAP = 0.4
#: Samples per practice render.
BATCH = 12


def choose_samples(notes: pd.DataFrame, per_group: int, seed: int) -> pd.DataFrame:
    """Up to ``per_group`` notes of every (instrument, group), drawn with ``seed``.

    Examples
    --------
    >>> notes = pd.DataFrame({"note_id": list("abcde"), "instrument": "violin",
    ...                       "group": ["g", "g", "g", "h", "h"]})
    >>> sorted(choose_samples(notes, 2, 0)["group"].tolist())
    ['g', 'g', 'h', 'h']
    """
    if per_group < 1:
        raise ParameterError(f"per_group={per_group} must be >= 1")
    rng = np.random.default_rng(seed)
    picks = []
    for _key, rows in notes.groupby(["instrument", "group"], sort=True):
        take = rows if len(rows) <= per_group else rows.iloc[
            np.sort(rng.choice(len(rows), per_group, replace=False))]
        picks.append(take)
    return pd.concat(picks, ignore_index=True) if picks else notes.iloc[:0]


def practice_targets(samples: pd.DataFrame, instrument: str) -> tuple[pd.DataFrame,
                                                                      pd.DataFrame]:
    """Targets and choices that play each sample once, alone, with a rest after it."""
    from data_schemas.instruments import instrument_facts
    from data_schemas.sampling import validate_choices, validate_targets

    facts = instrument_facts(instrument)
    dur = samples["duration"].to_numpy(np.float64)
    onset = 0.2 + np.r_[0.0, np.cumsum(dur + GAP)[:-1]]
    le = samples["effective_string_length"].to_numpy(np.float64)
    targets = pd.DataFrame({
        "onset": onset, "duration": dur, "midi_pitch": samples["midi_pitch"].to_numpy(),
        "string": samples["string"].to_numpy(),
        "finger_ratio": np.clip(1.0 - le / facts.scale_length, 0.0, 0.8),
        "effective_string_length": le, "dynamic": samples["dynamic"].to_numpy(np.float64),
        "technique": samples["technique"].to_numpy(),
        "bow_direction": samples["bow_direction"].to_numpy(),
        "slur_position": samples["slur_position"].to_numpy(),
        "run_position": samples["run_position"].to_numpy(),
        "group": samples["group"].to_numpy()})
    n = len(samples)
    choices = pd.DataFrame({
        "target_index": np.arange(n, dtype=np.int32), "note_id": samples["note_id"].to_numpy(),
        "group": samples["group"].to_numpy(), "sample_group": samples["group"].to_numpy(),
        "mirrored": np.zeros(n, bool), "sample_duration": dur, "target_cost": 0.0,
        "continuity_cost": 0.0, "gesture_cost": 0.0})
    return (validate_targets(targets, source="practice targets"),
            validate_choices(choices, source="practice choices"))


def judge_batch(samples: pd.DataFrame, instrument: str, database, *, seed: int,
                sample_rate: int = 44100) -> pd.DataFrame:
    """Play one batch of samples and return their :data:`DB_QUALITY` rows."""
    from data_schemas.instruments import instrument_facts
    from gesture_db.assemble import assemble_actions
    from pipelines.listening.evaluate import evaluate
    from pipelines.methods.playable import to_playable
    from pipelines.methods.sampled_beta import to_beta_range
    from pipelines.methods.sampled_bite import bite_chosen
    from pipelines.methods.sampled_bow import assembly_options
    from pipelines.methods.sampling_db import adapt_forces
    from pipelines.perform.config import load_config
    from synth.render import render_with_diagnostics

    config = load_config()
    targets, choices = practice_targets(samples, instrument)
    actions = assemble_actions(targets, choices, database.contours,
                               bow_length=instrument_facts(instrument).bow_length,
                               **assembly_options(config, database.search_config, instrument))
    actions = adapt_forces(actions, instrument, database.search_config,
                           sampled_from=instrument)
    actions, _ = to_beta_range(actions, targets, choices, instrument, database.search_config)
    actions, _ = to_playable(actions, targets, choices, instrument, database.search_config)
    # each practice note starts a stroke from rest, and bites as it would in a piece
    actions, _ = bite_chosen(actions, targets, choices, [None] * len(targets), config,
                             database.search_config, instrument)
    audio, diag = render_with_diagnostics(actions, instrument=instrument, engine="modal",
                                          sample_rate=sample_rate, seed=seed)
    found = evaluate(audio, actions, sample_rate=sample_rate, diagnostics=diag,
                     instrument=instrument)["notes"]
    starts = np.array([n["start"] for n in found], np.float64)
    rows = []
    for k, onset in enumerate(targets["onset"].to_numpy()):
        near = np.flatnonzero(np.abs(starts - onset) < 0.5 * GAP) if starts.size else []
        counts = np.zeros(5, np.int64)
        helm, attack = [], []
        for j in near:
            hist = found[j]["sustained_class_histogram"]
            counts += np.array([hist[str(c)] for c in range(1, 6)], np.int64)
            helm.append(found[j]["helmholtz_share"])
            attack.append(found[j]["attack_ms"])
        rows.append(dict(note_id=str(samples["note_id"].iloc[k]), instrument=instrument,
                         class_counts=counts.astype(np.int32).tolist(),
                         helmholtz_share=float(np.nanmean(helm)) if np.isfinite(
                             np.asarray(helm, float)).any() else float("nan"),
                         attack_ms=float(attack[0]) if attack else float("nan"), seed=seed))
    return pd.DataFrame(rows)


def judge_samples(db_path: str | os.PathLike, *, per_group: int = 4, seed: int = 0,
                  sample_rate: int = 44100, progress: bool = False) -> pd.DataFrame:
    """Judge up to ``per_group`` samples of every group and instrument; store the histograms.

    Parameters
    ----------
    db_path : path-like
        Gesture database (``arco build-db``).
    per_group : int
        Samples judged per (instrument, group); the others get the mean cost of the
        instrument's judged samples.
    seed : int
        Seed of the sample choice and of the renders.
    sample_rate : int, Hz
    progress : bool
        Progress bar over the practice renders.

    Returns
    -------
    pandas.DataFrame
        The :data:`data_schemas.gesture_db.DB_QUALITY` rows written.
    """
    from tqdm import tqdm

    from pipelines.methods.sampling_db import open_database

    database = open_database(db_path, predictors=False)
    chosen = choose_samples(database.db.notes(), per_group, seed)
    batches = [(inst, rows.iloc[a:a + BATCH]) for inst, rows in chosen.groupby("instrument")
               for a in range(0, len(rows), BATCH)]
    parts = [judge_batch(rows, str(inst), database, seed=seed + k, sample_rate=sample_rate)
             for k, (inst, rows) in enumerate(tqdm(batches, desc="judge", unit="render",
                                                   disable=not progress))]
    quality = pd.concat(parts, ignore_index=True)
    database.db.write_quality(quality)
    return quality


__all__ = ["choose_samples", "judge_batch", "judge_samples", "practice_targets"]
