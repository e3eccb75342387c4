"""``arco demo``: the whole story on built-in data, written under ``out/``.

1. the instrument alone: a pentachord on every string of violin, viola and cello
   (``scales.wav``, one bowing plot per instrument, pitch errors in the report);
2. the performance rules: the opening of Mozart's quartet K. 421 (bundled, public domain),
   every part on its own instrument (``mozart-k421-rules.wav``, actions, bowing plot);
3. gesture sampling against feedback control: simulate a small set of bowing recordings,
   build the gesture database, train the listening models of violin, viola and cello
   (quick settings; reused when ``out/models`` already holds them), play the quartet's
   opening with feedback control, every part with its own instrument's models
   (``mozart-k421-feedback.wav``), and compare rules, feedback, sampling and open-loop
   sampling on the first violin's opening with two seeds (``report/index.html``,
   ``report/results.json``);
4. a quick run of the held-out protocol (``pipelines/data/heldout.toml``: its first two
   excerpts, four measures each, all four parts, two seeds) when the shared data folder is
   there (``$ARCO_SHARED_DATA`` or ``../shared/data``; the report says when it is not):
   ``heldout/index.html``.

``report.md`` says what was played and what was measured. Each step of part 3 is an
``arco`` command, printed as it runs, so it can be repeated on one's own data.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING

from pipelines.cli.help import RawDescriptionFormatter
from pipelines.cli.outputs import output_dir
from pipelines.cli.types import non_negative_int, positive_int
from pipelines.score.bundled import bundled_score
from synth.strings import INSTRUMENT_NAMES

if TYPE_CHECKING:  # pragma: no cover - typing only
    import numpy as np

SAMPLE_RATE = 44100
#: Scale notes further than this from their pitch are flagged in the report, cents.
PITCH_TOLERANCE_CENTS = 10.0
DEMO_MEASURES = (1, 8)
#: Seeds of the demo's comparisons.
DEMO_SEEDS = 2
#: The quick held-out run: the protocol's first excerpts, measures of each.
HELDOUT_QUICK = (2, 4)
#: Simulated performers per instrument of the demo's recordings.
DEMO_PERFORMERS = 3
#: Simulated notes per instrument of the demo's database (quick settings for viola, cello).
DEMO_INSTRUMENT_NOTES = {"violin": 2000, "viola": 1000, "cello": 1000}
#: Samples per group and instrument the demo judges by playing them (``arco db judge``).
DEMO_JUDGED_PER_GROUP = 3


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``demo`` sub-command."""
    p = subparsers.add_parser("demo", help="run the demo pipeline on built-in data",
                              description=__doc__,
                              formatter_class=RawDescriptionFormatter)
    p.add_argument("-o", "--output", type=Path, default=Path("out"),
                   help="directory for the audio, plots and report")
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed of every step")
    p.add_argument("--workers", type=positive_int, default=2, help="worker processes")
    p.add_argument("--skip-learning", action="store_true",
                   help="only the instrument and the rules (no database, training, comparison)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Play the scales and the quartet excerpt; write audio, plots and the report."""
    out: Path = output_dir(args.output)
    out.mkdir(parents=True, exist_ok=True)
    report = ["# Arco demo", ""]
    report += scales(out, args.seed)
    report += quartet_rules(out, args.seed)
    if not args.skip_learning:
        report += sampling_story(out, args.seed, args.workers)
        report += heldout_story(out, args.workers)
    (out / "report.md").write_text("\n".join(report) + "\n")
    print(f"wrote audio, plots and {out / 'report.md'}")
    return 0


def scales(out: Path, seed: int) -> list[str]:
    """Render the pentachord on every string of each instrument; return report lines."""
    import numpy as np

    from data_schemas.actions import write_actions
    from pipelines.audio_io import write_audio
    from pipelines.perform.scale import scale_actions
    from pipelines.reports.plots import plot_bowing
    from synth.render import render_actions
    from synth.strings import load_instrument

    pieces = []
    lines = ["## The instrument", "", "Pentachord (0, 2, 4, 5, 7 semitones) on every string, "
             "detache, beta 0.1, 0.3 m/s, each string's reference force; notes last at least "
             "60 periods of the lowest open string, pitch measured over their settled part "
             "(from 45 % of the note to 0.1 s before its end). "
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
    from data_schemas.actions import write_actions
    from pipelines.audio_io import write_audio
    from pipelines.methods.rules import render
    from pipelines.perform.config import load_config
    from pipelines.reports.plots import plot_bowing
    from pipelines.score import read_score
    from pipelines.score.select import choose_parts, select_measures

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


def sampling_story(out: Path, seed: int, workers: int) -> list[str]:
    """Simulate recordings, build the database, train, compare the four methods."""
    import json

    from pipelines.cli.main import main

    performers = DEMO_PERFORMERS
    notes = DEMO_INSTRUMENT_NOTES["violin"]
    steps = [
        ["simulate-recordings", "--instrument", name, "--notes", str(count),
         "--performers", str(performers), "--seed", str(seed + 1 + k),
         "-o", str(out / "recordings" / name)]
        for k, (name, count) in enumerate(DEMO_INSTRUMENT_NOTES.items())]
    steps += [
        ["build-db", *(str(out / "recordings" / name) for name in DEMO_INSTRUMENT_NOTES),
         "-o", str(out / "db"), "--workers", str(workers)],
        ["db", "info", str(out / "db"), "--no-plots"],
        ["db", "judge", str(out / "db"), "--per-group", str(DEMO_JUDGED_PER_GROUP),
         "--seed", str(seed)],
        *(["train", "--instrument", name, "--teacher", "auto", "--quick",
           "-o", str(out / "models"), "--workers", str(workers), "--seed", str(seed)]
          for name in INSTRUMENT_NAMES),
        ["render", str(bundled_score()), "--method", "feedback", "--models", str(out / "models"),
         "--all-parts", "--start-measure", str(DEMO_MEASURES[0]), "--end-measure",
         str(DEMO_MEASURES[1]), "--seed", str(seed), "--quiet",
         "-o", str(out / f"{bundled_score().stem}-feedback.wav")],
        ["compare", str(bundled_score()), "--methods", "rules,feedback,sampling,sampling-open",
         "--db", str(out / "db"), "--models", str(out / "models"), "--part", "0",
         "--start-measure", str(DEMO_MEASURES[0]), "--end-measure", str(DEMO_MEASURES[1]),
         "--seeds", str(DEMO_SEEDS), "--workers", str(workers), "--quiet",
         "-o", str(out / "report")],
    ]
    timings = []
    for step in steps:
        print("$ arco " + " ".join(step), flush=True)
        start = time.perf_counter()
        code = main(step)
        if code != 0:
            raise RuntimeError(f"demo step failed: arco {' '.join(step)}")
        label = {"db": f"db {step[1]}", "train": f"train {step[2]}"}.get(step[0], step[0])
        timings.append((label, time.perf_counter() - start))
    results = json.loads((out / "report" / "results.json").read_text())
    stem = bundled_score().stem
    lines = ["## Gesture sampling against feedback control", "",
             f"{notes} violin, {DEMO_INSTRUMENT_NOTES['viola']} viola and "
             f"{DEMO_INSTRUMENT_NOTES['cello']} cello simulated notes by {performers} "
             f"performers each -> gesture database ({DEMO_JUDGED_PER_GROUP} samples per "
             "group and instrument judged by playing them) -> "
             "listening models for the 16 string x dynamic pairs of violin, viola and cello "
             f"(all four parts of K. 421 played with feedback control: `{stem}-feedback.wav`) "
             f"-> the first violin of K. 421, measures {DEMO_MEASURES[0]}-{DEMO_MEASURES[1]}, "
             f"played four ways with {DEMO_SEEDS} seeds. Full report with audio and bowing "
             "plots: `report/index.html`.", "", f"**{results['verdict']}**", "",
             *interval_table(results), "",
             "Steps: " + ", ".join(f"{name} {sec:.0f} s" for name, sec in timings), ""]
    return lines


def interval_table(results: dict) -> list[str]:
    """Markdown table of a comparison's headline figures: mean [95 % interval]."""
    cols = (("helmholtz_share", "Helmholtz share", 3), ("attack_ms_p90", "attack p90 (ms)", 0),
            ("sustained_class3_share", "class-3 share", 3),
            ("sustained_class5_share", "class-5 share", 3))
    lines = ["| method | " + " | ".join(c[1] for c in cols) + " | render (s, not scored) |",
             "|---" * (len(cols) + 2) + "|"]
    for method, figs in results["summary"].items():
        cells = []
        for key, _, digits in cols:
            d = figs.get(key)
            cells.append("n/a" if not d or d["mean"] is None else
                         f"{d['mean']:.{digits}f} [{d['low']:.{digits}f}, {d['high']:.{digits}f}]")
        seconds = results["timing"].get(method, {}).get("render_seconds")
        lines.append(f"| {method} | " + " | ".join(cells)
                     + f" | {'' if seconds is None else format(seconds, '.1f')} |")
    for method, message in results["failed"].items():
        lines.append(f"| {method} | not compared: {message} |" + " |" * len(cols))
    return lines


def heldout_story(out: Path, workers: int) -> list[str]:
    """The quick held-out run, or a line saying why it did not run."""
    import json

    from data_schemas.errors import ParameterError
    from pipelines.cli.main import main
    from pipelines.reports.heldout import shared_data_dir
    from synth.listening.classifier import DYNAMICS, pair_key

    head = ["## The held-out protocol (quick run)", ""]
    try:
        shared_data_dir()
    except ParameterError as exc:
        print(f"held-out protocol skipped: {exc}")
        return [*head, f"Not run: {exc}.", ""]
    models = out / "models"
    listening = all((models / f"{pair_key(i, 0, DYNAMICS[0])}.json").exists()
                    for i in ("violin", "viola", "cello"))
    methods = "rules,feedback,sampling,sampling-open" if listening else "rules,sampling-open"
    first, measures = HELDOUT_QUICK
    step = ["compare", "--heldout", "--excerpts", str(first), "--measures", str(measures),
            "--seeds", str(DEMO_SEEDS), "--methods", methods, "--db", str(out / "db"),
            "--models", str(models), "--workers", str(workers), "--quiet",
            "-o", str(out / "heldout")]
    print("$ arco " + " ".join(step), flush=True)
    start = time.perf_counter()
    if main(step) != 0:
        raise RuntimeError(f"demo step failed: arco {' '.join(step)}")
    results = json.loads((out / "heldout" / "results.json").read_text())
    note = "" if listening else (" Feedback and sampling with the loop need viola and cello "
                                 "models too (`arco train --instrument viola|cello`); only "
                                 "the open-loop methods ran.")
    return [*head, f"The first {first} excerpts of `pipelines/data/heldout.toml`, "
            f"{measures} measures each, all four parts, {DEMO_SEEDS} seeds "
            f"({time.perf_counter() - start:.0f} s): `heldout/index.html`.{note} The full "
            "protocol: `arco compare --heldout --db DB --models DIR -o DIR`.", "",
            f"**{results['verdict']}**", "", *interval_table(results), "",
            *(f"- {t['verdict']}" for t in results.get("instruments", {}).values()), ""]


def _pitch_rows(name: str, audio: np.ndarray, events) -> list[str]:
    """Each note's pitch (YIN over its settled part) against the equal-tempered target."""
    import numpy as np
    from music21.pitch import Pitch

    from synth.playability import yin_pitch

    rows = []
    for t0, t1, label in zip(events["measure_start"], events["measure_end"], events["label"],
                             strict=True):
        a, b = int(t0 * SAMPLE_RATE), int(t1 * SAMPLE_RATE)
        target = Pitch(label).frequency
        f0 = yin_pitch(audio[a:b], SAMPLE_RATE, target)
        cents = 1200 * np.log2(f0 / target)
        flag = "" if abs(cents) <= PITCH_TOLERANCE_CENTS else " **off**"
        rows.append(f"| {name} | {label} | {cents:+.1f}{flag} |")
    return rows
