"""Measure natural harmonics on the modal instrument: sounding pitch, the partials' suppression.

Every string of the violin (``--instrument`` viola, cello) bows its 2nd, 3rd and 4th
natural harmonics (the finger touching at 1/n from the nut, ``finger_touch``) for 1.5 s as
the rules do at beta 0.1: beta = 0.1 x ``[harmonics] segment_beta`` / n (at least
``min_beta``), 0.3 m/s, ``[harmonics] force`` x the string's reference force (seed 0,
44.1 kHz, the synthesized body). From 0.5 s to 1.4 s: the pitch (median of librosa's YIN) in
cents re n times the open string's nominal frequency, and the margin (dB) from the strongest
partial with a node at the finger (multiples of n) to the strongest without one (partials
1..3n of the open string). ``--dynamics`` instead reads and renders a violin score of
diamonds (D5, A5, E5, G4, C4: the D, A, G strings' 2nd, the A string's 3rd, the G
string's 4th harmonics) at pp, p, mf, f and ff with the rules (seed 0) and gives each
note's YIN pitch re its sounding pitch and its level (dB RMS). Artificial harmonics (a
stopping finger a fifth above the open string and a touching finger at 1/n of the stopped
length, ``touch_ratio``, n = 3, 4, 5: a fifth, a fourth, a major third above the stopped
note) are measured the same way, re n times the stopped note's nominal frequency, the
stopping finger at its nominal place (no correction by ear) and the bow as for a natural
harmonic of the same n on the stopped length. ``--artificial-score`` instead renders a
violin score of artificial harmonics (a stopped note and a diamond a fourth, fifth or
major third above) with the rules (seed 0, mf), whose stopping finger is placed by ear, and
gives each note's YIN pitch re its sounding pitch and its level. ``--json`` prints one JSON
object on stdout. About 15 s."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pipelines.perform.config import load_config  # noqa: E402
from synth.instrument import Instrument  # noqa: E402
from synth.strings import load_instrument  # noqa: E402

SR = 44100
STROKE = 1.5  # s


def harmonic(string: int, n: int, settings: dict, instrument: str = "violin",
             ) -> dict[str, float]:
    """Pitch error (cents) and partial margin (dB) of the n-th harmonic of one string."""
    const = load_instrument(instrument).strings[string]
    t = np.array([0.0, 0.05, STROKE - 0.05, STROKE])
    ramp = np.array([0.0, 1.0, 1.0, 0.0])
    actions = pd.DataFrame({"time": t, "string": string, "finger_ratio": 1.0 / n,
                            "bow_force": settings["force"] * const.reference_force * ramp,
                            "bow_velocity": 0.3 * ramp,
                            "beta": max(0.1 * settings["segment_beta"] / n,
                                        settings["min_beta"]),
                            "bow_position": 0.5, "pluck": False, "finger_touch": True})
    audio, _ = Instrument(instrument, seed=0).render(actions)
    f_open = 440.0 * 2.0 ** ((const.midi_pitch - 69) / 12.0)
    return _measure(audio, f_open, n)


def _measure(audio: np.ndarray, f_base: float, n: int) -> dict[str, float]:
    """Cents re n x f_base (YIN median) and the margin of the multiples of n (dB)."""
    import librosa

    steady = audio[int(0.5 * SR):int((STROKE - 0.1) * SR)].astype(np.float64)
    f0 = librosa.yin(steady, fmin=n * f_base / 1.5, fmax=n * f_base * 1.5, sr=SR,
                     frame_length=4096)
    spectrum = np.abs(np.fft.rfft(steady * np.hanning(steady.size)))
    freqs = np.fft.rfftfreq(steady.size, 1.0 / SR)
    k = np.arange(1, 3 * n + 1)
    db = np.array([20.0 * np.log10(spectrum[(freqs > 0.97 * j * f_base)
                                            & (freqs < 1.03 * j * f_base)].max() + 1e-30)
                   for j in k])
    return {"cents": round(float(1200.0 * np.log2(np.median(f0) / (n * f_base))), 2),
            "margin_db": round(float(db[k % n == 0].max() - db[k % n != 0].max()), 1)}


#: Semitones of the stopping finger above the open string in the artificial figures.
ARTIFICIAL_STOP = 7


def artificial(string: int, n: int, settings: dict, instrument: str = "violin",
               ) -> dict[str, float]:
    """Pitch error (cents) and partial margin (dB) of an artificial harmonic on one string."""
    const = load_instrument(instrument).strings[string]
    stop = 1.0 - 2.0 ** (-ARTIFICIAL_STOP / 12.0)
    t = np.array([0.0, 0.05, STROKE - 0.05, STROKE])
    ramp = np.array([0.0, 1.0, 1.0, 0.0])
    actions = pd.DataFrame({"time": t, "string": string, "finger_ratio": stop,
                            "bow_force": settings["force"] * const.reference_force * ramp,
                            "bow_velocity": 0.3 * ramp,
                            "beta": max(0.1 * settings["segment_beta"] / n,
                                        settings["min_beta"]),
                            "bow_position": 0.5, "pluck": False,
                            "touch_ratio": stop + (1.0 - stop) / n})
    audio, _ = Instrument(instrument, seed=0).render(actions)
    f_stopped = 440.0 * 2.0 ** ((const.midi_pitch + ARTIFICIAL_STOP - 69) / 12.0)
    return _measure(audio, f_stopped, n)


#: Stopped note and diamond of the artificial-harmonic score (violin).
ARTIFICIAL_SCORE = (("A4", "D5"), ("D4", "G4"), ("E4", "A4"), ("E5", "A5"), ("A4", "E5"),
                    ("D5", "A5"), ("G4", "B4"), ("C5", "E5"))


def artificial_score_run(path: Path) -> dict[str, dict[str, float]]:
    """Render the artificial-harmonic score with the rules; per note: cents and level."""
    import librosa
    from music21 import chord, dynamics, pitch, stream, tempo
    from music21 import instrument as m21instrument

    from pipelines.methods.render import render_score

    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, m21instrument.Violin())
    measure = stream.Measure(number=1)
    measure.insert(0, tempo.MetronomeMark(number=60))
    measure.insert(0, dynamics.Dynamic("mf"))
    for low, high in ARTIFICIAL_SCORE:
        c = chord.Chord([low, high], quarterLength=1.5)
        c.notes[1].notehead = "diamond"
        measure.append(c)
    part.append(measure)
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    out = render_score(path, method="rules", seed=0)
    audio = out.audio.astype(np.float64)
    result = {}
    for (t0, end), (low, high) in zip(out.parts[0].events[["t0", "end"]].to_numpy(),
                                      ARTIFICIAL_SCORE, strict=False):
        stopped = pitch.Pitch(low).midi
        n = {7: 3, 5: 4, 4: 5}[pitch.Pitch(high).midi - stopped]
        target = n * 440.0 * 2.0 ** ((stopped - 69) / 12.0)
        seg = audio[int((t0 + 0.2) * SR):int((end - 0.05) * SR)]
        f0 = librosa.yin(seg, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=2048)
        result[f"{low}+{high} (n={n})"] = {
            "cents": round(float(1200.0 * np.log2(np.median(f0) / target)), 2),
            "level_db": round(float(10.0 * np.log10(np.mean(seg**2))), 1)}
    return result


#: Diamond (touching pitch) -> sounding MIDI pitch on the violin.
DIAMONDS = {"D5": 74, "A5": 81, "E5": 88, "G4": 67, "C4": 79}
LEVELS = ("pp", "p", "mf", "f", "ff")


def dynamics_run(path: Path) -> dict[str, dict[str, float]]:
    """Render the diamond score at five dynamics; per note: cents and level (dB RMS)."""
    import librosa
    from music21 import dynamics, note, stream, tempo
    from music21 import instrument as m21instrument

    from pipelines.methods.render import render_score

    part = stream.Part(id="P1")
    part.partName = "Violin"
    part.insert(0, m21instrument.Violin())
    for k, level in enumerate(LEVELS):
        measure = stream.Measure(number=k + 1)
        if k == 0:
            measure.insert(0, tempo.MetronomeMark(number=60))
        measure.insert(0, dynamics.Dynamic(level))
        for name in DIAMONDS:
            n = note.Note(name, quarterLength=0.8)
            n.notehead = "diamond"
            measure.append(n)
        part.append(measure)
    score = stream.Score()
    score.insert(0, part)
    score.write("musicxml", fp=str(path))
    out = render_score(path, method="rules", seed=0)
    audio = out.audio.astype(np.float64)
    result = {}
    for i, (t0, end) in enumerate(out.parts[0].events[["t0", "end"]].to_numpy()):
        name, midi = list(DIAMONDS.items())[i % len(DIAMONDS)]
        target = 440.0 * 2.0 ** ((midi - 69) / 12.0)
        seg = audio[int((t0 + 0.2) * SR):int((end - 0.05) * SR)]
        f0 = librosa.yin(seg, fmin=target / 1.5, fmax=target * 1.5, sr=SR, frame_length=2048)
        result[f"{LEVELS[i // len(DIAMONDS)]} {name}"] = {
            "cents": round(float(1200.0 * np.log2(np.median(f0) / target)), 2),
            "level_db": round(float(10.0 * np.log10(np.mean(seg**2))), 1)}
    return result


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--instrument", default="violin", choices=("violin", "viola", "cello"))
    p.add_argument("--segment-beta", type=float, help="override [harmonics] segment_beta")
    p.add_argument("--force", type=float, help="override [harmonics] force")
    p.add_argument("--dynamics", action="store_true",
                   help="render a score of diamonds at pp..ff with the rules instead")
    p.add_argument("--artificial-score", action="store_true",
                   help="render a score of artificial harmonics with the rules instead")
    args = p.parse_args(argv)
    if args.dynamics or args.artificial_score:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            out = (dynamics_run(Path(tmp) / "diamonds.musicxml") if args.dynamics
                   else artificial_score_run(Path(tmp) / "artificial.musicxml"))
        print(json.dumps(out) if args.json else "\n".join(
            f"{k}: {v['cents']:+6.2f} cents, {v['level_db']:.1f} dB" for k, v in out.items()))
        return 0
    settings = dict(load_config()["harmonics"])
    for key in ("segment_beta", "force"):
        if getattr(args, key) is not None:
            settings[key] = getattr(args, key)
    names = load_instrument(args.instrument).strings
    out = {f"{names[s].name}{n}": harmonic(s, n, settings, args.instrument)
           for s in range(4) for n in (2, 3, 4)}
    out.update({f"{names[s].name}+{ARTIFICIAL_STOP}:{n}": artificial(s, n, settings,
                                                                      args.instrument)
                for s in range(4) for n in (3, 4, 5)})
    if args.json:
        print(json.dumps(out))
        return 0
    for key, row in out.items():
        what = (f"harmonic {key[1:]}" if "+" not in key else
                f"artificial harmonic {key.split(':')[1]} of the stopped fifth")
        print(f"{args.instrument} {key[0]} string, {what}: {row['cents']:+6.2f} cents, "
              f"other partials {row['margin_db']:.1f} dB down")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
