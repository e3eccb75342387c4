"""Write an ensemble render: the stereo master in a room and the parts' stems beside it."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

from pipelines.ensemble.config import part_pans
from pipelines.ensemble.mixdown import MixReport, mixdown
from pipelines.ensemble.spool import AudioSpool
from pipelines.ensemble.wav_stream import audio_writer


def stem_paths(output: str | os.PathLike, parts: list) -> list[Path]:
    """``OUT-<index>-<instrument>.wav`` beside ``OUT.wav`` for each part.

    Examples
    --------
    >>> from types import SimpleNamespace as P
    >>> [p.name for p in stem_paths("q/mix.wav", [P(part_index=0, instrument="violin")])]
    ['mix-0-violin.wav']
    """
    base = Path(output)
    return [base.with_name(f"{base.stem}-{p.part_index}-{p.instrument}{base.suffix}")
            for p in parts]


def write_ensemble(output, path: str | os.PathLike, *, sample_rate: int,
                   ensemble: dict[str, Any], progress: bool = False,
                   spool: AudioSpool | None = None) -> MixReport:
    """Mix a :class:`~pipelines.methods.result.MethodOutput`'s parts into ``path``.

    The parts' audio is read from ``spool`` when they were rendered into one (the way
    ``arco render --all-parts`` keeps memory flat); otherwise each part's audio goes to a
    temporary mono file and is released from memory (its ``audio`` and the output's mono
    mix become None). :func:`mixdown` then streams the master and the stems
    (:func:`stem_paths`).

    Returns
    -------
    MixReport
    """
    path = Path(path)
    pans = part_pans(ensemble, len(output.parts))
    output.audio = None
    if spool is not None:
        return mixdown([spool.path(p.part_index) for p in output.parts], path, pans=pans,
                       ensemble=ensemble, stems=stem_paths(path, output.parts),
                       progress=progress)
    with tempfile.TemporaryDirectory(dir=path.absolute().parent, prefix=".parts-") as folder:
        sources = []
        for k, part in enumerate(output.parts):
            source = Path(folder) / f"{k}.wav"
            with audio_writer(source, sample_rate, 1) as out:
                out.write(part.audio)
            part.audio = None
            sources.append(source)
        return mixdown(sources, path, pans=pans, ensemble=ensemble,
                       stems=stem_paths(path, output.parts), progress=progress)
