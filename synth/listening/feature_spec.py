"""What the listening features are: frame sizes, the feature columns and their constants.

Shared by the batch and streaming paths (:mod:`synth.listening.features`) and the hop
kernel (:mod:`synth.listening.features_kernel`), which writes the columns by the indices
named here.
"""

from __future__ import annotations

#: Samples per analysis frame and per hop (at 44.1 kHz: 23 ms and 5.8 ms).
WINDOW = 1024
HOP = 256
#: Share of the magnitude sum below the roll-off frequency.
ROLL_PERCENT = 0.85
#: Clip of ``pitch_diff`` and of ``pitch_fine``, semitones.
PITCH_CLIP = 3.0
PITCH_FINE_CLIP = 0.1
#: Hops back that ``rms_slope`` compares the level with.
RMS_SLOPE_HOPS = 7
FEATURE_NAMES = ("zcr", "centroid", "rolloff", "flux", "crest", "flatness", "rms_db",
                 "pitch_diff", "aperiodicity", "pitch_fine", "rms_slope")
#: Column of each feature in a feature row.
(COL_ZCR, COL_CENTROID, COL_ROLLOFF, COL_FLUX, COL_CREST, COL_FLATNESS, COL_RMS_DB,
 COL_PITCH_DIFF, COL_APERIODICITY, COL_PITCH_FINE, COL_RMS_SLOPE) = range(len(FEATURE_NAMES))
#: Floor of magnitudes and powers (and the zero-crossing dead band), as librosa's amin.
AMIN = 1e-10
#: Floor of the RMS before it is taken to dB (-160 dB).
RMS_FLOOR = 1e-8
#: YIN's absolute threshold on the cumulative-mean-normalised difference.
YIN_THRESHOLD = 0.15
