"""Write rendered audio atomically as WAV (32-bit float) or FLAC (24-bit).

WAV files are written by :func:`scipy.io.wavfile.write`, which adds no time-stamped chunk
(libsndfile's float WAVs carry a PEAK chunk with the writing time), so the same audio
gives the same file, byte for byte.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import scipy.io.wavfile
import soundfile as sf

from data_schemas.errors import ParameterError
from data_schemas.io import atomic_path

_FORMATS = {".wav": ("WAV", "FLOAT"), ".flac": ("FLAC", "PCM_24")}


def write_audio(path: str | os.PathLike, audio: np.ndarray, sample_rate: int) -> Path:
    """Write mono ``audio`` to ``path`` (``.wav``: float32, bit-exact; ``.flac``: 24-bit).

    Parameters
    ----------
    path : path-like
        Target file; its suffix picks the format.
    audio : np.ndarray [shape=(n,)]
        Samples, nominally within [-1, 1] (FLAC clips outside).
    sample_rate : int, Hz

    Returns
    -------
    pathlib.Path
    """
    path = Path(path)
    fmt = _FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ParameterError(f"{path}: unsupported audio format '{path.suffix}' "
                             f"(use {', '.join(_FORMATS)})")
    data = np.asarray(audio, dtype=np.float32)
    if fmt[0] == "FLAC":
        data = np.clip(data, -1.0, 1.0)
    with atomic_path(path) as tmp:
        if fmt[0] == "WAV":
            scipy.io.wavfile.write(tmp, sample_rate, data)
        else:
            sf.write(tmp, data, sample_rate, format=fmt[0], subtype=fmt[1])
    return path
