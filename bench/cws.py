"""Leave-one-recording-out figures of the ``cws`` engine (cluster-weighted sampling).

For each annotated recording (default: the shared Bach Violin Dataset in
``$ARCO_SHARED_DATA/bach-violin``, else ``<repo>/../shared/data/bach-violin``, else
``/work/shared/data/bach-violin``, or ``--data DIR`` laid out the same way; with
``--audio-db DB`` the frames come from that audio-frame database) the
engine is trained on the **other** recordings and plays the left-out recording's aligned
notes of the first ``--seconds``. The actions are made from the notes directly, one constant
stroke per note (documented simplification, no performance rules): the highest open string
at or below the pitch, the finger ratio of the interval, bow velocity +-0.3 m/s alternating
note by note, force 0.6 N (the violinist's mf), beta 0.1. The notes are made monophonic
first (a chord keeps its highest note; every note ends where the next starts).

Figures per left-out recording, beside FluidR3 (the aligned notes as MIDI through fluidsynth;
null with the reason when fluidsynth or the soundfont is missing) and the real recording:

- ``mfcc_frechet``: MFCC-frame Frechet distance to the left-out recording
  (:func:`pipelines.reports.timbre.measure` and ``frechet_distance``, as ``bench/timbre.py``);
- ``pitch_error_cents``: per sustained note (>= 0.3 s), the median YIN f0 over the note's
  middle half against the nominal pitch (A4 = 440 Hz); median and 90th percentile of the
  absolute error, and the share within 10 cents;
- ``clicks``: sample-to-sample jumps above 6x the local RMS slope
  (:func:`synth.clicks.find_clicks`);
- ``real_time_factor``: audio seconds per second of ``engine.render`` (the model trained
  before; training time reported apart).

Without ``--audio-db`` the database of the recordings is built first by
:func:`gesture_db.audio_build.build_audio_database` (what ``arco build-db --audio`` runs) into
``--cache DIR`` (default: a temporary folder; a kept cache is reused and only changed
recordings are analysed again), and each fold leaves its recording out of it.

``--json`` prints exactly one JSON object on stdout; progress goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from data_schemas.errors import ArcoError  # noqa: E402
from pipelines.reports import baselines, recordings, timbre  # noqa: E402
from pipelines.reports.json_safe import json_safe  # noqa: E402
from pipelines.reports.leave_out import shared_recordings_folder, without  # noqa: E402

#: JSON-safe figures, rounded to 3 decimals.
clean = partial(json_safe, digits=3)

SAMPLE_RATE = 44100
ANALYSIS_RATE = 22050
ANALYSIS_HOP = 256
SUSTAINED_S = 0.3


def say(*parts: Any) -> None:
    print(*parts, file=sys.stderr, flush=True)


def shared_folder() -> Path:
    """The shared bach-violin folder (as ``arco compare --engines`` finds it)."""
    return shared_recordings_folder()


def monophonic(table: pd.DataFrame) -> pd.DataFrame:
    """One note at a time: a chord (starts within 30 ms) keeps its highest note, and every
    note ends where the next starts."""
    t = table.sort_values(["start_s", "midi_pitch"], ascending=[True, False], kind="stable")
    kept = []
    for row in t.itertuples(index=False):
        if kept and row.start_s - kept[-1]["start_s"] < 0.03:
            continue
        kept.append(row._asdict())
    out = pd.DataFrame(kept)
    out["end_s"] = np.minimum(out["end_s"], out["start_s"].shift(-1).fillna(np.inf))
    return out.reset_index(drop=True)


def note_actions(notes: pd.DataFrame, instrument: str = "violin") -> pd.DataFrame:
    """Constant strokes, 10 ms rows, one per note (see the module docstring)."""
    from data_schemas.instruments import finger_ratio, instrument_facts

    open_strings = np.asarray(instrument_facts(instrument).open_strings)
    rows = []
    for i, n in enumerate(notes.itertuples(index=False)):
        string = int(np.searchsorted(open_strings, n.midi_pitch, side="right") - 1)
        string = max(string, 0)
        semis = min(max(float(n.midi_pitch) - open_strings[string], 0.0), 27.0)
        ratio = float(finger_ratio(semis))
        times = np.round(np.arange(n.start_s, max(n.end_s - 0.005, n.start_s + 0.01), 0.01), 4)
        v = 0.3 if i % 2 == 0 else -0.3
        rows += [(t, string, ratio, 0.6, v, 0.1, 0.5, False) for t in times]
    a = pd.DataFrame(rows, columns=["time", "string", "finger_ratio", "bow_force",
                                    "bow_velocity", "beta", "bow_position", "pluck"])
    return a.sort_values("time", kind="stable").reset_index(drop=True)


def pitch_errors(audio: np.ndarray, notes: pd.DataFrame) -> dict[str, Any]:
    """YIN pitch of each sustained note's middle half against its nominal pitch (cents)."""
    import librosa

    low = librosa.resample(np.asarray(audio, float), orig_sr=SAMPLE_RATE,
                           target_sr=ANALYSIS_RATE)
    f0 = librosa.yin(low, fmin=180.0, fmax=2500.0, sr=ANALYSIS_RATE, frame_length=1024,
                     hop_length=ANALYSIS_HOP)
    times = librosa.frames_to_time(np.arange(f0.size), sr=ANALYSIS_RATE,
                                   hop_length=ANALYSIS_HOP)
    errors = []
    for n in notes.itertuples(index=False):
        if n.end_s - n.start_s < SUSTAINED_S:
            continue
        q = (n.end_s - n.start_s) / 4
        sel = (times >= n.start_s + q) & (times <= n.end_s - q)
        if sel.sum() < 3:
            continue
        want = 440.0 * 2.0 ** ((float(n.midi_pitch) - 69) / 12)
        errors.append(1200 * np.log2(float(np.median(f0[sel])) / want))
    e = np.abs(np.array(errors))
    if not e.size:
        return {"notes": 0, "median_abs": None, "p90_abs": None, "within_10": None}
    return {"notes": int(e.size), "median_abs": float(np.median(e)),
            "p90_abs": float(np.percentile(e, 90)), "within_10": float(np.mean(e <= 10))}


def figures(audio: np.ndarray, table: pd.DataFrame, mono: pd.DataFrame,
            real: timbre.TimbreMeasure | None) -> dict[str, Any]:
    from synth.clicks import find_clicks

    m = timbre.measure(audio, SAMPLE_RATE, table)
    return {"mfcc_frechet": None if real is None else timbre.frechet_distance(m.mfcc, real.mfcc),
            "centroid_hz": m.figures["centroid_hz"], "h6_10_db": m.figures["h6_10_db"],
            "pitch_error_cents": pitch_errors(audio, mono),
            "clicks": int(find_clicks(audio, SAMPLE_RATE).size)}


def leave_one_out(db: Any, rec: recordings.Recording, args: argparse.Namespace,
                  workdir: Path) -> dict[str, Any]:
    from synth.cws.engine import trained_model
    from synth.engines import get_engine

    table = recordings.first_seconds(
        recordings.read_aligned_notes(rec.notes, rec.alignment), args.seconds)
    mono = monophonic(table)
    n = int(round(args.seconds * SAMPLE_RATE))
    real_audio = recordings.read_audio(rec.audio, seconds=args.seconds, sample_rate=SAMPLE_RATE)
    real = timbre.measure(real_audio, SAMPLE_RATE, table)
    out: dict[str, Any] = {"notes": len(table), "monophonic_notes": len(mono),
                           "real": figures(real_audio, table, mono, None)}
    train_db = without(db, rec.name, workdir / f"db-without-{rec.name}")
    t0 = time.perf_counter()
    trained_model(train_db, n_clusters=args.clusters, seed=args.seed)
    out["train_s"] = time.perf_counter() - t0
    engine = get_engine("cws", "violin", sample_rate=SAMPLE_RATE, seed=args.seed,
                        audio_db=train_db, n_clusters=args.clusters)
    actions = note_actions(mono)
    t0 = time.perf_counter()
    audio, _ = engine.render(actions, tail=0.5)
    wall = time.perf_counter() - t0
    audio = recordings.fit_length(audio.astype(np.float64), n)
    out["cws"] = {**figures(audio, table, mono, real), "real_time_factor": args.seconds / wall}
    again, _ = engine.render(actions, tail=0.5)
    out["cws"]["bit_identical_rerender"] = bool(np.array_equal(
        recordings.fit_length(again.astype(np.float64), n), audio))
    try:
        midi = recordings.write_aligned_midi(table, workdir / f"{rec.name}.mid")
        fluid = recordings.fit_length(baselines.fluidsynth_render(midi, SAMPLE_RATE), n)
        out["fluidr3"] = figures(fluid, table, mono, real)
    except baselines.PeerMissingError as exc:
        out["fluidr3"] = {"mfcc_frechet": None, "reason": str(exc)}
    if args.out:
        from pipelines.audio_io import write_audio

        write_audio(Path(args.out) / f"{rec.name}-cws.wav",
                    timbre.normalise_loudness(audio, SAMPLE_RATE, table), SAMPLE_RATE)
    say(f"  {rec.name}: cws frechet {out['cws']['mfcc_frechet']:.0f}, fluidr3 "
        f"{out['fluidr3']['mfcc_frechet']}, rtf {out['cws']['real_time_factor']:.1f}")
    return out


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--audio-db", metavar="DB", help="an audio-frame database (arco build-db)")
    p.add_argument("--data", metavar="DIR",
                   help="recordings laid out like bach-violin (audio/, notes/, alignments/; "
                        "default: the shared bach-violin folder)")
    p.add_argument("--seconds", type=float, default=30.0,
                   help="render the left-out recording's first N seconds (default 30)")
    p.add_argument("--cache", metavar="DIR",
                   help="build (and keep) the audio-frame database here (default: temporary)")
    p.add_argument("--clusters", type=int, default=12, help="clusters (default 12)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", metavar="DIR", help="keep the loudness-normalised renders")
    return p.parse_args(argv)


def open_database(args: argparse.Namespace, folder: Path, tmp: Path) -> Any:
    """The audio-frame database: ``--audio-db``, else built from ``folder``."""
    from data_schemas.audio_frames import read_audio_database

    if args.audio_db:
        return read_audio_database(args.audio_db)
    from gesture_db.audio_build import build_audio_database

    out = Path(args.cache) if args.cache else tmp / "audio-db"
    t0 = time.perf_counter()
    build_audio_database([folder], out, progress=False)
    say(f"audio-frame database {out} built in {time.perf_counter() - t0:.0f} s")
    return read_audio_database(out)


def run(args: argparse.Namespace) -> dict[str, Any]:
    started = time.perf_counter()
    folder = Path(args.data) if args.data else shared_folder()
    recs = recordings.dataset_recordings(folder)
    per = {}
    with tempfile.TemporaryDirectory() as tmp:
        db = open_database(args, folder, Path(tmp))
        for rec in recs:
            say(f"{rec.name} left out:")
            per[rec.name] = leave_one_out(db, rec, args, Path(tmp))
    mean = {src: {k: float(np.mean([p[src][k] for p in per.values()
                                    if p[src].get(k) is not None] or [np.nan]))
                  for k in ("mfcc_frechet", "clicks", "real_time_factor")}
            for src in ("cws", "fluidr3")}
    return clean({"settings": {"seconds": args.seconds, "clusters": args.clusters,
                               "seed": args.seed,
                               "database": args.audio_db or args.cache or "built (temporary)"},
                  "recordings": per, "mean": mean,
                  "elapsed_s": time.perf_counter() - started})


def main(argv: list[str] | None = None) -> int:
    try:
        args = parse_args(argv)
        report = run(args)
    except ArcoError as exc:
        print(f"cws: error: {exc}", file=sys.stderr)
        return 2
    print(json.dumps(report, indent=1) if args.json else json.dumps(report["mean"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
