"""Parts' audio kept on disk as each part is rendered, so a quartet holds one part at most."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pipelines.ensemble.wav_stream import audio_writer


class AudioSpool:
    """Write each rendered part's mono audio to ``folder`` and let go of it.

    Parameters
    ----------
    folder : path-like
        An existing folder (temporary: the caller removes it).
    sample_rate : int, Hz

    Examples
    --------
    >>> import tempfile, soundfile
    >>> spool = AudioSpool(tempfile.mkdtemp(), 44100)
    >>> spool.put(2, np.ones(5, np.float32)).size, soundfile.info(spool.path(2)).frames
    (0, 5)
    """

    def __init__(self, folder: str | os.PathLike, sample_rate: int) -> None:
        self.folder, self.sample_rate = Path(folder), sample_rate
        self.paths: dict[int, Path] = {}

    def put(self, part_index: int, audio: np.ndarray) -> np.ndarray:
        """Write ``audio`` as part ``part_index``'s file; return an empty float32 array."""
        path = self.folder / f"part-{int(part_index)}.wav"
        with audio_writer(path, self.sample_rate, 1) as out:
            out.write(audio)
        self.paths[int(part_index)] = path
        return np.zeros(0, np.float32)

    def path(self, part_index: int) -> Path:
        """The file of part ``part_index`` (KeyError if it was not put)."""
        return self.paths[int(part_index)]
