"""Real-world MusicXML: three OpenScore string quartets (whole works) read completely.

The data lives outside the repository: ``$ARCO_SHARED_DATA``, else ``<repo>/../shared/data``,
else ``/work/shared/data``. A missing directory fails the test with that message.
"""

from __future__ import annotations

import numpy as np
import pytest
from _data import shared_data

from pipelines.perform.config import load_config
from pipelines.perform.rules import perform_part
from pipelines.score.musicxml import notes_from_music21, parse_musicxml

#: The three smallest files of the corpus (music21 parses ~1,000 notes/s).
QUARTETS = (
    "Mozart-Wolfgang-Amadeus-String-Quartet-No.15-in-D-minor-K.421417b-Op.-10-No.-2-sq7294793.mxl",
    "Haydn-Joseph-String-Quartet-in-D-minor-Hob.III76-Op.76-No.2-sq12772795.mxl",
    "Haydn-Joseph-String-Quartet-in-B-flat-major-Hob.III67-Op.64-No.3-sq7123582.mxl",
)


@pytest.fixture(scope="module", params=QUARTETS, ids=lambda n: n.split("-String")[0])
def quartet(request):
    path = shared_data() / "openscore-quartets" / request.param
    score = parse_musicxml(path)
    counted = sum(len(n.pitches) for n in score.recurse().notes
                  if "Unpitched" not in n.classSet)
    return path, counted, notes_from_music21(score, source=str(path))


def test_reads_every_note_music21_counts(quartet):
    _, counted, notes = quartet
    assert len(notes) == counted
    assert notes["part_index"].nunique() == 4
    assert list(notes.groupby("part_index")["instrument"].first()) == \
        ["violin", "violin", "viola", "cello"]
    assert (notes["onset"].diff().fillna(0)[notes["part_index"].diff().fillna(0) == 0] >= 0).all()
    assert notes["slur_id"].notna().any() and notes["staccato"].any()


def test_quartet_parts_play_within_the_bow(quartet):
    _, _, notes = quartet
    cfg = load_config()
    part = notes[notes["part_index"] == 3]
    perf = perform_part(part, cfg, transpose_octaves=True)
    a = perf.actions
    assert a["bow_position"].between(0, 1).all()
    assert np.all(np.diff(a["time"]) >= 0)
    assert a["time"].max() >= part["onset"].max()
