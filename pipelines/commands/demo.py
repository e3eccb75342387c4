"""``arco demo``: play the most complete pipeline on built-in data, writing under ``out/``.

1. the instrument alone: a pentachord on every string of violin, viola and cello
   (``scales.wav``, one bowing plot per instrument, pitch errors in the report);
2. the performance rules: the opening of Mozart's quartet K. 421 (bundled, public domain),
   every part on its own instrument (``mozart-k421-rules.wav``, actions, bowing plot).

``report.md`` says what was played and what was measured.
"""

from __future__ import annotations

import argparse
import time
from importlib import resources
from pathlib import Path

import numpy as np

from data_schemas.actions import write_actions
from pipelines.audio_io import write_audio
from pipelines.plots import plot_bowing
from pipelines.scale import scale_actions
from synth import INSTRUMENT_NAMES, render_actions
from synth.playability import yin_pitch
from synth.strings import load_instrument

SAMPLE_RATE = 44100
DEMO_SCORE = "mozart-k421.mxl"
DEMO_MEASURES = (1, 8)


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``demo`` sub-command."""
    p = subparsers.add_parser("demo", help="run the demo pipeline on built-in data",
                              description=__doc__)
    p.add_argument("-o", "--output", type=Path, default=Path("out"))
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=run)


def bundled_score(name: str = DEMO_SCORE) -> Path:
    """Path of a score bundled with Arco (``pipelines/data``)."""
    return Path(str(resources.files("pipelines") / "data" / name))


def run(args: argparse.Namespace) -> int:
    """Play the scales and the quartet excerpt; write audio, plots and the report."""
    out: Path = args.output
    out.mkdir(parents=True, exist_ok=True)
    report = ["# Arco demo", ""]
    report += scales(out, args.seed)
    report += quartet_rules(out, args.seed)
    (out / "report.md").write_text("\n".join(report) + "\n")
    print(f"wrote audio, plots and {out / 'report.md'}")
    return 0


def scales(out: Path, seed: int) -> list[str]:
    """Render the pentachord on every string of each instrument; return report lines."""
    pieces = []
    lines = ["## The instrument", "", "Pentachord (0, 2, 4, 5, 7 semitones) on every string, "
             "detache, beta 0.1, 0.3 m/s, each string's reference force. "
             "Audio: `scales.wav`; bowing: `scales_<instrument>.png`.", "",
             "| instrument | note | pitch error (cents) |", "|---|---|---|"]
    for name in INSTRUMENT_NAMES:
        actions, events = scale_actions(name)
        audio = render_actions(actions, instrument=name, seed=seed)
        write_actions(actions, out / f"scales_{name}_actions.parquet")
        plot_bowing(actions, events, out / f"scales_{name}.png",
                    title=f"Arco demo: {name} scale", string_names=tuple(
                        s.name for s in load_instrument(name).strings))
        lines.extend(_pitch_rows(name, audio, events))
        pieces.append(audio)
        print(f"scales: {name} done")
    write_audio(out / "scales.wav", np.concatenate(pieces), SAMPLE_RATE)
    return [*lines, ""]


def quartet_rules(out: Path, seed: int) -> list[str]:
    """Render the bundled quartet's opening with the rules; return report lines."""
    from pipelines.render import choose_parts, render, select_measures
    from pipelines.rules_config import load_config
    from pipelines.score import read_score

    score = bundled_score()
    notes = select_measures(read_score(score), *DEMO_MEASURES)
    start = time.perf_counter()
    result = render(notes, load_config(None), parts=choose_parts(notes, None, True), seed=seed,
                    progress=False)
    seconds = time.perf_counter() - start
    stem = score.stem + "-rules"
    write_audio(out / f"{stem}.wav", result.audio, result.sample_rate)
    for part in result.parts:
        write_actions(part.performance.actions, out / f"{stem}-{part.part_index}.parquet")
    first = result.parts[0]
    plot_bowing(first.performance.actions, first.performance.events, out / f"{stem}.png",
                title=f"{score.name} m. {DEMO_MEASURES[0]}-{DEMO_MEASURES[1]}: "
                      f"{first.part_name}, rules")
    audio_s = result.audio.size / result.sample_rate
    print(f"rules: {score.name} {audio_s:.1f} s of audio in {seconds:.1f} s")
    return ["## The performance rules", "",
            f"Mozart, String Quartet K. 421 (OpenScore, CC0), measures {DEMO_MEASURES[0]}-"
            f"{DEMO_MEASURES[1]}, all four parts: `{stem}.wav` ({audio_s:.1f} s, rendered in "
            f"{seconds:.1f} s), actions `{stem}-<part>.parquet`, first violin's bowing "
            f"`{stem}.png`.", ""]


def _pitch_rows(name: str, audio: np.ndarray, events) -> list[str]:
    """Measure each note's pitch (YIN over its middle) against the equal-tempered target."""
    from music21.pitch import Pitch

    rows = []
    for t0, label in zip(events["t0"], events["label"], strict=True):
        a = int((t0 + 0.15) * SAMPLE_RATE)
        b = int((t0 + 0.35) * SAMPLE_RATE)
        target = Pitch(label).frequency
        f0 = yin_pitch(audio[a:b], SAMPLE_RATE, target)
        rows.append(f"| {name} | {label} | {1200 * np.log2(f0 / target):+.1f} |")
    return rows
