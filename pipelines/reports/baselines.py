"""Reference renders of aligned notes that are not Arco: a sawtooth and FluidR3 (fluidsynth).

The sawtooth is additive (harmonics k f0 below Nyquist with amplitude 1/k, zero phase),
the textbook bowed-string idealisation (Helmholtz motion) without body or noise. FluidR3 is
the General MIDI soundfont's sampled violin, played by the ``fluidsynth`` program (a peer
run as a separate process, reverb and chorus off).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from data_schemas.errors import ArcoError

#: Where Debian's fluid-soundfont-gm installs FluidR3.
FLUIDR3 = Path("/usr/share/sounds/sf2/FluidR3_GM.sf2")
#: Linear fade-in and fade-out of each sawtooth note (s).
FADE = 0.005


class PeerMissingError(ArcoError):
    """A peer program or its data is not installed (the message says what to install)."""


def sawtooth(f0: float, n: int, sample_rate: int) -> np.ndarray:
    """``n`` samples of a band-limited sawtooth at ``f0`` (Hz): sum of sin(2 pi k f0 t)/k.

    Parameters
    ----------
    f0 : float, Hz
    n : int
    sample_rate : int, Hz

    Returns
    -------
    numpy.ndarray [shape=(n,)]
        Peak about 1.85 (the Gibbs overshoot of pi/2 * 1.18).
    """
    t = np.arange(n) / sample_rate
    out = np.zeros(n)
    for k in range(1, int((sample_rate / 2.0 - 1e-9) // f0) + 1):
        out += np.sin(2.0 * np.pi * k * f0 * t) / k
    return out


def sawtooth_notes(table: pd.DataFrame, n: int, sample_rate: int, *,
                   tuning_a4: float = 440.0, fade: float = FADE) -> np.ndarray:
    """Every aligned note as a sawtooth at its pitch and performed time, mixed.

    Parameters
    ----------
    table : pandas.DataFrame
        Aligned notes (``start_s, end_s, midi_pitch``).
    n : int
        Length of the output (samples).
    sample_rate : int, Hz
    tuning_a4 : float, Hz
    fade : float, s
        Linear fade at each end of each note.

    Returns
    -------
    numpy.ndarray [shape=(n,)]
    """
    out = np.zeros(n)
    for start, end, pitch in zip(table["start_s"], table["end_s"], table["midi_pitch"],
                                 strict=True):
        a, b = int(round(start * sample_rate)), min(int(round(end * sample_rate)), n)
        if b <= a:
            continue
        note = sawtooth(tuning_a4 * 2.0 ** ((pitch - 69.0) / 12.0), b - a, sample_rate)
        ramp = np.minimum(1.0, np.minimum(np.arange(b - a) + 1,
                                          np.arange(b - a, 0, -1)) / max(fade * sample_rate, 1))
        out[a:b] += note * ramp
    return out


def fluidsynth_render(midi: str | os.PathLike, sample_rate: int, *,
                      soundfont: str | os.PathLike = FLUIDR3,
                      timeout: float = 300.0) -> np.ndarray:
    """Play a MIDI file with ``fluidsynth`` and a soundfont; mono float64.

    Parameters
    ----------
    midi : path-like
        The MIDI file (its program changes choose the instruments).
    sample_rate : int, Hz
    soundfont : path-like
        ``.sf2`` file (default FluidR3 GM).
    timeout : float, s

    Returns
    -------
    numpy.ndarray [shape=(n,)]

    Raises
    ------
    PeerMissingError
        ``fluidsynth`` is not on PATH or the soundfont is missing.
    ArcoError
        fluidsynth failed (its last message is quoted).
    """
    import soundfile as sf

    program = shutil.which("fluidsynth")
    if program is None:
        raise PeerMissingError("fluidsynth is not installed (apt-get install fluidsynth)")
    if not Path(soundfont).is_file():
        raise PeerMissingError(f"{soundfont}: soundfont not found (apt-get install "
                          "fluid-soundfont-gm)")
    with tempfile.TemporaryDirectory() as tmp:
        wav = Path(tmp) / "fluidsynth.wav"
        run = subprocess.run([program, "-ni", "-F", str(wav), "-r", str(sample_rate), "-R", "0",
                              "-C", "0", str(soundfont), str(midi)],
                             capture_output=True, text=True, timeout=timeout, check=False)
        if run.returncode != 0 or not wav.is_file():
            last = (run.stderr.strip() or run.stdout.strip() or "no output").splitlines()[-1]
            raise ArcoError(f"fluidsynth failed on {midi} ({last[:200]})")
        data, rate = sf.read(str(wav), dtype="float64", always_2d=True)
    if rate != sample_rate:
        raise ArcoError(f"fluidsynth wrote {rate} Hz instead of {sample_rate} Hz")
    return data.mean(axis=1)
