"""``arco compare --engines``: engines against real recordings, leaving one recording out.

For each annotated recording (a folder laid out like bach-violin: ``audio/``, ``notes/``,
``alignments/``) the aligned notes of the first ``seconds`` are written as a MIDI file whose
ticks are milliseconds, read back as a score and performed by the rules (seed ``seed``,
violin, octaves transposed into range); the one actions table is then played by every
engine asked for. Engines built on recorded audio (``frames``, ``cws``) get the audio-frame
database **without** that recording (:func:`pipelines.reports.leave_out.without`), or with
``leave_out="performer"`` without every recording of its performer (the recording name up
to the first ``_``: a performer the database has never heard, as a recording from outside
would be). Beside
them: FluidR3 (the MIDI file through fluidsynth; figures null with the reason when it is
missing) and the real recording itself (its ``mfcc_frechet`` is the floor: its mean
distance to the other performers' recordings).

Every source is measured the same way: :func:`pipelines.reports.timbre.measure` (MFCC-frame
Frechet distance to the recording, centroid, harmonics 6-10 and 11-20 re harmonic 1),
:func:`pipelines.reports.vibrato.vibrato_figures` (share, extent, rate, intonation spread),
:func:`pipelines.reports.loudness.level_range_db`, the yardstick's median attack from the
audio at the aligned notes' times (:func:`pipelines.listening.evaluate.evaluate`),
:func:`pipelines.reports.joins.click_ratio`
(largest jump over the local RMS slope) and
:func:`pipelines.reports.joins.pitch_error_cents` (median error on sustained stretches
against the pitch the rules' actions ask for); each engine also gets its real-time factor
(audio seconds per wall-clock second of the render alone: ``frames`` and ``cws`` render
twice, the first fitting or indexing the database, decoding the recordings and compiling,
and the second, timed, must be bit-identical to it; the modal engine compiles on a
throw-away instance first).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from data_schemas.errors import ParameterError
from pipelines.reports import baselines, loudness, recordings, timbre, vibrato

SAMPLE_RATE = 44100
#: Engines that play recorded audio and need the audio-frame database.
DATABASE_ENGINES = ("frames", "cws")
#: Figures per source and recording, in report order.
FIGURES = ("mfcc_frechet", "centroid_hz", "h6_10_db", "h11_20_db", "vibrato_share",
           "vibrato_extent_cents", "vibrato_rate_hz", "intonation_spread_cents",
           "attack_ms", "level_range_db", "click_ratio", "pitch_error_cents",
           "real_time_factor")
TAIL_S = 0.5
#: What is left out of the database while a recording is measured.
LEAVE_OUT = ("recording", "performer")


def withheld(recording: str, names: Sequence[str], leave_out: str = "recording") -> list[str]:
    """The recordings the engines must not hear while ``recording`` is measured.

    Examples
    --------
    >>> names = ["ann_1", "ann_2", "bob_1"]
    >>> withheld("ann_1", names), withheld("ann_1", names, "performer")
    (['ann_1'], ['ann_1', 'ann_2'])
    """
    if leave_out not in LEAVE_OUT:
        raise ParameterError(f"--leave-out {leave_out!r}: choose from {', '.join(LEAVE_OUT)}")
    if leave_out == "recording":
        return [recording]
    return sorted(n for n in names if performer(n) == performer(recording))


def check_engines(engines: Sequence[str], audio_db: object | None) -> list[str]:
    """The engine names, checked: registered, and a database where one is needed.

    Raises
    ------
    ParameterError
        An unknown engine, none at all, or ``frames``/``cws`` without ``audio_db``.

    Examples
    --------
    >>> check_engines(["modal"], None)
    ['modal']
    >>> check_engines(["modal", "cws"], None)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    data_schemas.errors.ParameterError: --engines cws needs --audio-db ADB ...
    """
    from synth.engines import engine_names

    names = list(dict.fromkeys(e.strip() for e in engines if e.strip()))
    if not names:
        raise ParameterError("--engines: give at least one engine")
    bad = [e for e in names if e not in engine_names()]
    if bad:
        raise ParameterError(f"--engines: unknown engine {', '.join(bad)} (choose from "
                             f"{', '.join(engine_names())})")
    need = [e for e in names if e in DATABASE_ENGINES]
    if need and audio_db is None:
        raise ParameterError(f"--engines {','.join(need)} needs --audio-db ADB (arco build-db "
                             "--audio DIR -o ADB)")
    return names


def performance_actions(midi: Path, seed: int, sample_rate: int = SAMPLE_RATE):
    """The rules' actions table of a one-track MIDI file (violin, octaves into range)."""
    from pipelines.methods.rules import render
    from pipelines.perform.config import load_config
    from pipelines.score import read_score

    return render(read_score(midi), load_config(), parts=[0], seed=seed, audio=False,
                  sample_rate=sample_rate, transpose_octaves=True,
                  progress=False).parts[0].performance.actions


def target_pitch(actions, sample_rate: int = SAMPLE_RATE) -> tuple[np.ndarray, np.ndarray]:
    """(times s, f0 Hz with NaN where silent) the actions ask for, on a 512-sample grid."""
    from synth.frames.targets import PitchProfile, derive_targets

    flat = PitchProfile(np.array([0.0, 127.0]), np.zeros(2), np.full(2, 1000.0), (-99.0, 0.0))
    tg = derive_targets(actions, "violin", 512 / sample_rate, flat)
    return tg.times, tg.f0


def source_figures(audio: np.ndarray, table, real_mfcc: np.ndarray | None,
                   pitch: tuple[np.ndarray, np.ndarray]) -> tuple[dict[str, Any], np.ndarray]:
    """Every figure of one source's audio (the real recording: ``real_mfcc`` None)."""
    from pipelines.reports.joins import click_ratio, pitch_error_cents

    m = timbre.measure(audio, SAMPLE_RATE, table)
    f: dict[str, Any] = {k: m.figures.get(k) for k in ("centroid_hz", "h6_10_db", "h11_20_db")}
    f["mfcc_frechet"] = None if real_mfcc is None else timbre.frechet_distance(m.mfcc, real_mfcc)
    f.update({k: v for k, v in vibrato.vibrato_figures(audio, SAMPLE_RATE, table).items()
              if k in FIGURES})
    f["attack_ms"] = attack_ms(audio, table)
    f["level_range_db"] = loudness.level_range_db(audio, SAMPLE_RATE, table)
    f["click_ratio"] = click_ratio(audio, SAMPLE_RATE)[0]
    pe = pitch_error_cents(audio, SAMPLE_RATE, *pitch)
    f["pitch_error_cents"] = pe["median_abs_cents"]
    f["pitch_within_10_cents"] = pe["share_within_10_cents"]
    return f, m.mfcc


def attack_ms(audio: np.ndarray, table) -> float | None:
    """Median attack (ms) of the audio at the aligned notes' times (None: not measurable).

    The yardstick's audio-only path: :func:`pipelines.listening.evaluate.evaluate` with
    ``timed_notes``.
    """
    from pipelines.listening.evaluate import evaluate

    try:
        got = evaluate(audio, sample_rate=SAMPLE_RATE, timed_notes=table)["piece"]
    except ParameterError:
        return None
    value = got["attack_ms_median"]
    return float(value) if np.isfinite(value) else None


def play_engine(name: str, actions, db: Any, recording: str, seed: int,
                workdir: Path, leave_out: str = "recording") -> tuple[np.ndarray, dict[str, Any]]:
    """One engine's render of the actions and its real-time factor.

    Database engines play ``db`` without :func:`withheld` (its caches in ``workdir``).
    """
    from synth.engines import get_engine
    from synth.render import render_actions

    options: dict[str, Any] = {}
    info: dict[str, Any] = {}
    if name in DATABASE_ENGINES:
        from pipelines.reports.leave_out import without_all

        gone = withheld(recording, sorted(db.audio_paths), leave_out)
        options["audio_db"] = without_all(db, gone, workdir / f"db-without-{'+'.join(gone)}")
        info["database_recordings"] = sorted(options["audio_db"].audio_paths)
    t0 = time.perf_counter()
    engine = get_engine(name, "violin", sample_rate=SAMPLE_RATE, seed=seed, **options)
    if name in DATABASE_ENGINES:
        # a first whole render fits or indexes the database, decodes the recordings it
        # uses and compiles the kernels; the second is timed (and must be identical)
        first = render_actions(actions, instrument=engine, tail=TAIL_S, source=recording)
    else:  # the modal engine compiles on its own instance: the timed one starts from rest
        get_engine(name, "violin", sample_rate=SAMPLE_RATE).render(actions.iloc[:2], tail=0.01)
        first = None
    t1 = time.perf_counter()
    audio = render_actions(actions, instrument=engine, tail=TAIL_S, source=recording)
    wall = time.perf_counter() - t1
    info["setup_s"] = t1 - t0
    info["render_s"] = wall
    info["real_time_factor"] = (audio.size / SAMPLE_RATE) / max(wall, 1e-9)
    if first is not None:
        info["bit_identical_rerender"] = bool(first.tobytes() == audio.tobytes())
    return np.asarray(audio, np.float64), info


def measure_recording(rec: recordings.Recording, engines: Sequence[str], db: Any, *,
                      seconds: float, seed: int, workdir: Path, keep: Path | None = None,
                      log: Callable[..., None] = lambda *a: None,
                      leave_out: str = "recording") -> tuple[dict, np.ndarray]:
    """Figures of every source for one left-out recording (and the real MFCC frames)."""
    table = recordings.first_seconds(
        recordings.read_aligned_notes(rec.notes, rec.alignment), seconds)
    if table.empty:
        raise ParameterError(f"{rec.alignment}: no note starts in the first {seconds} s")
    if db is not None and rec.name not in db.audio_paths:
        raise ParameterError(f"recording {rec.name!r} ({rec.audio}) is not in the audio-frame "
                             f"database {getattr(db, 'root', '')} (it holds "
                             f"{', '.join(sorted(db.audio_paths))}): leave-one-out needs it")
    n = int(round(seconds * SAMPLE_RATE))
    midi = recordings.write_aligned_midi(table, workdir / f"{rec.name}.mid")
    actions = performance_actions(midi, seed)
    pitch = target_pitch(actions)
    real_audio = recordings.read_audio(rec.audio, seconds=seconds, sample_rate=SAMPLE_RATE)
    real, real_mfcc = source_figures(real_audio, table, None, pitch)
    out: dict[str, Any] = {"audio": str(rec.audio), "notes": len(table),
                           "figures": {"real": real}, "engines": {}}
    sources = {}
    for name in engines:
        audio, info = play_engine(name, actions, db, rec.name, seed, workdir, leave_out)
        out["engines"][name] = info
        sources[name] = (recordings.fit_length(audio, n), info["real_time_factor"])
    try:
        fluid = baselines.fluidsynth_render(midi, SAMPLE_RATE)
        sources["fluidr3"] = (recordings.fit_length(np.asarray(fluid, np.float64), n), None)
    except baselines.PeerMissingError as exc:
        out["figures"]["fluidr3"] = {**dict.fromkeys(FIGURES), "reason": str(exc)}
    for name, (audio, rtf) in sources.items():
        f, _ = source_figures(audio, table, real_mfcc, pitch)
        out["figures"][name] = {**f, "real_time_factor": rtf}
        if keep is not None:
            _write(keep / f"{rec.name}-{name}.wav", audio, table)
        log(f"  {name}: MFCC Frechet {f['mfcc_frechet']:.0f}"
            + (f", {rtf:.1f}x real time" if rtf else ""))
    return out, real_mfcc


def _write(path: Path, audio: np.ndarray, table) -> None:
    from pipelines.audio_io import write_audio

    write_audio(path, timbre.normalise_loudness(audio, SAMPLE_RATE, table), SAMPLE_RATE)


def performer(name: str) -> str:
    """Performer of a recording: its name up to the first ``_``."""
    return name.split("_")[0]


def set_floor(per: dict[str, dict], mfcc: dict[str, np.ndarray]) -> float | None:
    """Set each real recording's ``mfcc_frechet``; return the overall mean.

    A recording's floor is its mean distance to other performers' recordings (to all other
    recordings when there is one performer).
    """
    names = sorted(mfcc)
    across = []
    for a in names:
        others = [b for b in names if b != a and performer(b) != performer(a)] or \
            [b for b in names if b != a]
        d = [timbre.frechet_distance(mfcc[a], mfcc[b]) for b in others]
        per[a]["figures"]["real"]["mfcc_frechet"] = float(np.mean(d)) if d else None
        across += d
    return float(np.mean(across)) if across else None


def mean_figures(per: dict[str, dict]) -> dict[str, dict[str, float | None]]:
    """Each source's figures averaged over the recordings (missing ones left out)."""
    sources = list(dict.fromkeys(s for r in per.values() for s in r["figures"]))
    out = {}
    for s in sources:
        out[s] = {}
        for f in FIGURES:
            vals = [r["figures"][s].get(f) for r in per.values() if s in r["figures"]]
            vals = [v for v in vals if v is not None and np.isfinite(v)]
            out[s][f] = float(np.mean(vals)) if vals else None
    return out


def verdict(means: dict[str, dict[str, float | None]]) -> str:
    """One sentence: the sources ranked by mean MFCC Frechet distance (real left out).

    Examples
    --------
    >>> verdict({"real": {"mfcc_frechet": 900.0}, "modal": {"mfcc_frechet": 1100.0},
    ...          "frames": {"mfcc_frechet": 600.0}, "fluidr3": {"mfcc_frechet": None}})
    ... # doctest: +NORMALIZE_WHITESPACE
    'closest to the real recordings by MFCC Frechet: frames (mean 600), then modal (1100);
     fluidr3 not measured'
    """
    got = sorted(((v["mfcc_frechet"], s) for s, v in means.items()
                  if s != "real" and v.get("mfcc_frechet") is not None))
    missing = [s for s, v in means.items() if s != "real" and v.get("mfcc_frechet") is None]
    if not got:
        return "no source could be measured by MFCC Frechet"
    text = f"closest to the real recordings by MFCC Frechet: {got[0][1]} (mean {got[0][0]:.0f})"
    if len(got) > 1:
        text += ", then " + ", ".join(f"{s} ({d:.0f})" for d, s in got[1:])
    if missing:
        text += f"; {', '.join(missing)} not measured"
    return text


def compare_engines(engines: Sequence[str], recordings_dir: str | Path, out_dir: str | Path, *,
                    audio_db: str | Path | None = None, seconds: float = 30.0, seed: int = 0,
                    keep_audio: bool = True, progress: bool = True,
                    log: Callable[..., None] = lambda *a: None,
                    leave_out: str = "recording") -> dict[str, Any]:
    """Run the comparison and write its report into ``out_dir``.

    ``leave_out``: ``"recording"`` (the database engines never hear the measured
    recording) or ``"performer"`` (nor any other recording of its performer).

    The report: ``results.json``, ``index.html``, WAVs of every source and one bar chart
    per figure. Returns the results (``verdict`` included).

    Raises
    ------
    ParameterError
        Bad engines, a missing database, a recording the database does not hold, bad
        recordings, ``seconds <= 0``, an unknown ``leave_out`` or (``"performer"``) a
        performer who is all the database holds.
    """
    import tempfile

    from tqdm import tqdm

    from pipelines.reports.engine_report import write_engine_report

    engines = check_engines(engines, audio_db)
    withheld("", [], leave_out)  # checks the mode
    if not seconds > 0:
        raise ParameterError(f"--seconds {seconds} must be > 0")
    recs = recordings.dataset_recordings(recordings_dir)
    db = None
    if audio_db is not None:
        from data_schemas.audio_frames import read_audio_database

        db = read_audio_database(audio_db)
        missing = [r.name for r in recs if r.name not in db.audio_paths]
        if missing and any(e in DATABASE_ENGINES for e in engines):
            raise ParameterError(f"recordings {', '.join(missing)} of {recordings_dir} are not "
                                 f"in the audio-frame database {audio_db} (it holds "
                                 f"{', '.join(sorted(db.audio_paths))})")
    out = Path(out_dir)
    per, mfcc = {}, {}
    with tempfile.TemporaryDirectory() as tmp, tqdm(
            total=len(recs), desc="compare --engines", unit="recording",
            disable=not progress) as bar:
        for rec in recs:
            log(f"{rec.name} (left out):")
            per[rec.name], mfcc[rec.name] = measure_recording(
                rec, engines, db if any(e in DATABASE_ENGINES for e in engines) else None,
                seconds=seconds, seed=seed, workdir=Path(tmp),
                keep=out if keep_audio else None, log=log, leave_out=leave_out)
            bar.update(1)
    floor = set_floor(per, mfcc)
    means = mean_figures(per)
    results = {"settings": {"engines": engines, "recordings": str(recordings_dir),
                            "audio_db": None if audio_db is None else str(audio_db),
                            "seconds": seconds, "seed": seed, "sample_rate": SAMPLE_RATE,
                            "leave_out": leave_out},
               "sources": ["real", *engines, "fluidr3"], "figures": list(FIGURES),
               "recordings": per, "mean": means, "floor_between_recordings": floor,
               "verdict": verdict(means)}
    return write_engine_report(results, out)


__all__ = ["LEAVE_OUT", "check_engines", "compare_engines", "measure_recording", "verdict",
           "withheld"]
