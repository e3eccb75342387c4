"""Classify the words printed in a string part (techniques, bow regions, strings, tempo)."""

from __future__ import annotations

import re
from dataclasses import dataclass

#: Word patterns for playing techniques; ``None`` means back to ordinary arco.
_TECHNIQUE_PATTERNS: tuple[tuple[str, str | None], ...] = (
    (r"^(pizz|pizzicato)\b", "pizz"),
    (r"^(arco)\b", None),
    (r"^(col\s+legno|c\.\s*l\.)", "col_legno"),
    (r"^(sul\s+pont|sul\s+ponticello|s\.\s*p\.|am\s+steg)", "sul_ponticello"),
    (r"^(sul\s+tasto|s\.\s*t\.|am\s+griffbrett|flautando)", "sul_tasto"),
    (r"^(ord|ordinario|nat|naturale|norm|normale|modo\s+ordinario)\b", None),
)
_REGION_PATTERNS: tuple[tuple[str, str], ...] = (
    (r"^(frog|au\s+talon|am\s+frosch|al\s+tallone|tallone)\b", "frog"),
    (r"^(lower\s+half|l\.\s*h\.)", "lower_half"),
    (r"^(middle|m\.\s*b\.|mid\.?\s*bow|middle\s+of\s+the\s+bow|a\s+mezz)", "middle"),
    (r"^(upper\s+half|u\.\s*h\.)", "upper_half"),
    (r"^(tip|punta|a\s+punta|punta\s+d'arco|a\s+punta\s+d'arco|an\s+der\s+spitze"
     r"|à\s+la\s+pointe|a\s+la\s+pointe)", "tip"),
)
_ROMAN = {"i": 3, "ii": 2, "iii": 1, "iv": 0}
_TEXT_MARKS = {"cresc": 1, "crescendo": 1, "dim": -1, "dimin": -1, "diminuendo": -1,
               "decresc": -1, "decrescendo": -1}
#: Tempo words that return to the main tempo.
_A_TEMPO = re.compile(r"^(a\s+tempo|tempo\s+i|tempo\s+primo|tempo\s+1)\b")


@dataclass(frozen=True)
class Direction:
    """What a printed word asks for.

    Attributes
    ----------
    kind : str
        ``technique``, ``ordinario``, ``region``, ``string``, ``string_once``, ``hairpin``,
        ``a_tempo`` or ``other``.
    value : object
        Technique name (or None for arco), region name, string index from the top
        (``I`` = 0: highest), hairpin direction (+1 / -1), or the text.
    """

    kind: str
    value: object = None


def classify(text: str) -> list[Direction]:
    """Classify a printed word or phrase.

    Parameters
    ----------
    text : str
        The words, e.g. ``"pizz."``, ``"sul G"``, ``"cresc."``, ``"punta d'arco"``.

    Returns
    -------
    list of Direction
        Possibly several (``"arco, sul tasto"``); empty if nothing is recognised.
    """
    out: list[Direction] = []
    for piece in re.split(r"[,;/]|\s+e\s+|\s+and\s+", text.strip().lower()):
        piece = piece.strip().strip("()[]").strip()
        if not piece:
            continue
        out.extend(_classify_piece(piece))
    return out


def _classify_piece(piece: str) -> list[Direction]:
    for pattern, technique in _TECHNIQUE_PATTERNS:
        if re.match(pattern, piece):
            if technique is None and not piece.startswith("arco"):
                return [Direction("ordinario")]
            return [Direction("technique", technique)]
    for pattern, region in _REGION_PATTERNS:
        if re.match(pattern, piece):
            return [Direction("region", region)]
    match = re.match(r"^sul\s+(?:la\s+|il\s+)?([a-g]|i{1,3}|iv|do|re|la|mi|sol)\b\.?$", piece)
    if match:
        return [Direction("string", match.group(1))]
    if piece.rstrip(".") in ("i", "ii", "iii", "iv") and not piece.endswith("."):
        return [Direction("string_once", _ROMAN[piece])]
    word = re.match(r"^[a-zà-ü]+", piece)
    if word and word.group(0) in _TEXT_MARKS:
        return [Direction("hairpin", _TEXT_MARKS[word.group(0)])]
    if _A_TEMPO.match(piece):
        return [Direction("a_tempo")]
    return []


def tempo_from_words(text: str, table: dict[str, float]) -> float | None:
    """Return the tempo a tempo word implies, in quarter notes per minute, or None.

    Parameters
    ----------
    text : str
        E.g. ``"Allegro ma non troppo"``.
    table : dict
        Lower-case tempo words to quarter notes per minute (music21's default table).
    """
    words = re.sub(r"[^a-zà-ü ]", " ", text.lower()).split()
    for n in (3, 2, 1):
        for i in range(len(words) - n + 1):
            key = " ".join(words[i:i + n])
            if key in table:
                return float(table[key])
    return None
