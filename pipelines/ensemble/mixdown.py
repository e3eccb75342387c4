"""Mix parts into a stereo master in a room, block by block, with stems beside it.

Each part's mono audio is read from a WAV in blocks, panned (:mod:`synth.pan`), summed
into a dry stereo bus whose mono sum feeds the room (:mod:`synth.room`, overlap-add
convolution); the master is measured as it goes (:mod:`synth.lufs`) and written to a
temporary file, then scaled to the target loudness (lowered if its peak would pass the
ceiling) into the output. Stems are the parts panned, dry, at the master's gain, each as
long as the dry mix, so with no room the mix is their sum. Memory holds a few blocks and
the room's response, whatever the length.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import soundfile as sf
from tqdm import tqdm

from pipelines.ensemble.wav_stream import audio_writer
from synth.lufs import LoudnessMeter
from synth.pan import Panner
from synth.room import BlockConvolver, room_response

#: Frames per block (about 1.5 s at 44.1 kHz).
BLOCK = 65536


@dataclass
class MixReport:
    """What :func:`mixdown` wrote: loudness (LUFS) and peak (dBFS) after its gain (dB)."""

    loudness: float
    peak_db: float
    gain_db: float
    seconds: float
    limited: bool
    stems: list[Path] = field(default_factory=list)


def mixdown(sources: list[str | os.PathLike], output: str | os.PathLike, *,
            pans: list[float], ensemble: dict, stems: list[str | os.PathLike] | None = None,
            progress: bool = False) -> MixReport:
    """Mix mono WAV ``sources`` into the stereo ``output`` (and ``stems``), streaming.

    Parameters
    ----------
    sources : list of path-like
        One mono audio file per part, all at one sample rate.
    output : path-like
        The master (``.wav`` float32 or ``.flac``).
    pans : list of float
        Each part's position, -1 left .. +1 right.
    ensemble : dict
        Settings (:func:`pipelines.ensemble.config.load_ensemble`): ``seating.max_itd``,
        ``room`` (``kind``, ``rt60`` s, ``wet``, ``seed``), ``master`` (``loudness`` LUFS,
        ``ceiling`` dBFS).
    stems : list of path-like, optional
        Where to write each part's panned stereo stem.
    progress : bool

    Returns
    -------
    MixReport

    Examples
    --------
    >>> import scipy.io.wavfile
    >>> from pipelines.ensemble.config import load_ensemble
    >>> folder = Path(tempfile.mkdtemp())
    >>> t = np.arange(44100 * 2) / 44100
    >>> scipy.io.wavfile.write(folder / "a.wav", 44100, (0.1 * np.sin(2e3 * t)).astype("f4"))
    >>> report = mixdown([folder / "a.wav"], folder / "mix.wav", pans=[-0.7],
    ...                  ensemble=load_ensemble())
    >>> round(report.loudness, 1), report.peak_db <= -1.0, sf.info(folder / "mix.wav").channels
    (-18.0, True, 2)
    """
    room, master = ensemble["room"], ensemble["master"]
    infos = [sf.info(str(s)) for s in sources]
    rate = infos[0].samplerate
    panners = [Panner(p, rate, ensemble["seating"]["max_itd"]) for p in pans]
    n_dry = max(i.frames + p.latency for i, p in zip(infos, panners, strict=True))
    conv = None
    n_total = n_dry
    if room["kind"] != "none":
        conv = BlockConvolver(room_response(rate, rt60=room["rt60"], seed=room["seed"],
                                            wet=room["wet"]))
        n_total += conv.response.shape[0] - 1
    meter = LoudnessMeter(rate, 2)
    with tempfile.TemporaryDirectory(dir=Path(output).absolute().parent,
                                     prefix=".mix-") as folder:
        raw = Path(folder) / "raw.wav"
        with audio_writer(raw, rate, 2) as out:
            for block in _dry_blocks(sources, panners, n_total, rate, progress, "mix"):
                if conv is not None:
                    block = block + conv.process(block.sum(axis=1) / math.sqrt(2.0))
                meter.add(block)
                out.write(block)
        gain, limited = _gain(meter, master)
        _scaled_copy(raw, output, gain)
    written = []
    for k, (source, target) in enumerate(zip(sources, stems or [], strict=False)):
        panner = Panner(pans[k], rate, ensemble["seating"]["max_itd"])
        with audio_writer(target, rate, 2) as out:
            for block in _dry_blocks([source], [panner], n_dry, rate, False, "stem"):
                out.write(block * gain)
        written.append(Path(target))
    loudness = meter.integrated() + 20.0 * math.log10(gain)
    peak = 20.0 * math.log10(max(meter.peak * gain, 1e-12))
    return MixReport(loudness, peak, 20.0 * math.log10(gain), n_total / rate, limited, written)


def _dry_blocks(sources, panners, n_total: int, rate: int, progress: bool, label: str):
    """Blocks ``(n, 2)`` of the panned sum of ``sources``, zero-padded to ``n_total``."""
    files = [sf.SoundFile(str(s)) for s in sources]
    try:
        bar = tqdm(total=round(n_total / rate, 1), unit="s audio", desc=label,
                   disable=not progress)
        for start in range(0, n_total, BLOCK):
            n = min(BLOCK, n_total - start)
            block = np.zeros((n, 2))
            for f, panner in zip(files, panners, strict=True):
                x = f.read(n, dtype="float64", always_2d=True)[:, 0]
                block += panner.process(np.pad(x, (0, n - x.size)))
            bar.update(round(n / rate, 1))
            yield block
        bar.close()
    finally:
        for f in files:
            f.close()


def _gain(meter: LoudnessMeter, master: dict) -> tuple[float, bool]:
    """Gain to the target loudness, lowered so that the peak stays under the ceiling."""
    loudness = meter.integrated()
    gain = 1.0 if not math.isfinite(loudness) else 10.0 ** ((master["loudness"] - loudness)
                                                           / 20.0)
    ceiling = 10.0 ** (master["ceiling"] / 20.0)
    if meter.peak * gain > ceiling:
        return ceiling * (1.0 - 1e-6) / meter.peak, True
    return gain, False


def _scaled_copy(source: Path, target: str | os.PathLike, gain: float) -> None:
    with sf.SoundFile(str(source)) as f, audio_writer(target, f.samplerate, 2) as out:
        while True:
            block = f.read(BLOCK, dtype="float32", always_2d=True)
            if not len(block):
                break
            out.write(block * np.float32(gain))
