"""Write audio block by block: 32-bit float WAV (byte-exact) or 24-bit FLAC, atomically.

The WAV header is the one :func:`scipy.io.wavfile.write` writes for float data (``fmt``
chunk of 18 bytes with format 3, a ``fact`` chunk, then ``data``), so a streamed file and a
file written whole are the same bytes; its sizes are filled in when the writer closes. The
file is written under a temporary name and renamed when complete.
"""

from __future__ import annotations

import contextlib
import os
import struct
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from data_schemas.errors import ParameterError
from data_schemas.io import atomic_path


class _WavWriter:
    def __init__(self, handle, sample_rate: int, channels: int) -> None:
        self.handle, self.channels, self.frames = handle, channels, 0
        block = 4 * channels
        handle.write(b"RIFF\0\0\0\0WAVEfmt " + struct.pack(
            "<IHHIIHHH", 18, 3, channels, sample_rate, sample_rate * block, block, 32, 0))
        handle.write(b"fact" + struct.pack("<II", 4, 0) + b"data\0\0\0\0")

    def write(self, block: np.ndarray) -> None:
        data = np.asarray(block, dtype="<f4").reshape(-1, self.channels)
        for start in range(0, data.shape[0], 1 << 16):  # no byte copy of a whole part
            self.handle.write(data[start:start + (1 << 16)].tobytes())
        self.frames += data.shape[0]

    def close(self) -> None:
        size = self.frames * 4 * self.channels
        self.handle.seek(4)
        self.handle.write(struct.pack("<I", 4 + 26 + 12 + 8 + size))
        self.handle.seek(46)
        self.handle.write(struct.pack("<I", self.frames))
        self.handle.seek(54)
        self.handle.write(struct.pack("<I", size))


class _FlacWriter:
    def __init__(self, handle) -> None:
        self.handle = handle

    def write(self, block: np.ndarray) -> None:
        self.handle.write(np.clip(np.asarray(block, dtype=np.float32), -1.0, 1.0))


@contextlib.contextmanager
def audio_writer(path: str | os.PathLike, sample_rate: int,
                 channels: int) -> Iterator[_WavWriter | _FlacWriter]:
    """Open ``path`` (``.wav`` float32 or ``.flac`` 24-bit) for ``(n, channels)`` blocks.

    Examples
    --------
    >>> import tempfile, scipy.io.wavfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> x = np.arange(20, dtype=np.float32).reshape(10, 2) / 20
    >>> with audio_writer(folder / "a.wav", 44100, 2) as out:
    ...     out.write(x[:3]); out.write(x[3:])
    >>> scipy.io.wavfile.write(folder / "b.wav", 44100, x)
    >>> (folder / "a.wav").read_bytes() == (folder / "b.wav").read_bytes()
    True
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".wav", ".flac"):
        raise ParameterError(f"{path}: unsupported audio format '{path.suffix}' "
                             "(use .wav, .flac)")
    with atomic_path(path) as tmp:
        if suffix == ".wav":
            with open(tmp, "wb") as handle:
                writer = _WavWriter(handle, sample_rate, channels)
                yield writer
                writer.close()
        else:
            import soundfile as sf

            with sf.SoundFile(tmp, "w", sample_rate, channels, "PCM_24", format="FLAC") as f:
                yield _FlacWriter(f)
