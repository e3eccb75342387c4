"""The pitch calibration table: how far from its nominal pitch the instrument model sounds.

One row per instrument, string, finger position and dynamic level, measured by
``bench/calibrate_pitch.py`` (steady notes at the rules' bow lanes, finger at the nominal
position, YIN); the rules read it to place each stopped finger by ear
(``pipelines/perform/ear.py``).
"""

from __future__ import annotations

import pyarrow as pa

from data_schemas.spec import Column, TableSpec

PITCH_CALIBRATION = TableSpec(
    name="pitch_calibration",
    version="1.0",
    description="Bowed pitch of steady notes played by the instrument model at the rules' "
                "bow lanes with the finger at its nominal (equal-tempered) position, one row "
                "per instrument, string, finger position and dynamic level.",
    columns=(
        Column("instrument", pa.string(), "", "violin, viola or cello."),
        Column("string", pa.int8(), "1", "String index, 0 = lowest.", minimum=0, maximum=3),
        Column("semitone", pa.float64(), "semitone",
               "Finger position above the open string.", minimum=0.0, maximum=36.0),
        Column("level", pa.float64(), "1", "Dynamic level, 0 = pppp .. 5 = mf .. 9 = ffff.",
               minimum=0.0, maximum=9.0),
        Column("measured_cents", pa.float64(), "cent",
               "Median YIN pitch of the note's settled part re its nominal pitch (positive: "
               "sharp); null where the note did not settle.", nullable=True,
               minimum=-200.0, maximum=200.0),
        Column("cents", pa.float64(), "cent",
               "The pitch error the rules correct: a robust cubic of measured_cents in the "
               "finger position, per string and level.", minimum=-200.0, maximum=200.0),
        Column("key", pa.string(), "",
               "Hash of the string physics, bow lanes and engine settings it was measured "
               "with (stale when they change)."),
    ),
)
