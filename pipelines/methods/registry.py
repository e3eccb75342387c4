"""The rendering methods, by name: notes -> rendered parts (audio, actions, diagnostics).

A method is a :class:`Method` record: a name, a one-line summary, whether it needs a gesture
database (``--db``) or listening models (``--models``), and a ``render(notes, parts, **kw)``
callable returning one :class:`~pipelines.methods.result.PartOutput` per part. The built-in
ones (``rules``, ``feedback``, ``sampling``, ``sampling-open``) live in
:mod:`pipelines.methods.builtin` and are imported when a method first renders, so listing
the methods (``arco render --help``) imports nothing numeric. A new method is one module and
one :func:`register_method` call (or one entry in :data:`BUILTIN`). ``arco render``,
``arco compare`` and :func:`pipelines.render_score` all go through :func:`render_method`.

Examples
--------
>>> method_names()
['rules', 'feedback', 'sampling', 'sampling-open']
>>> get_method("feedback").needs_models, get_method("feedback").needs_db
(True, False)
>>> def silence(notes, parts, **settings):
...     return []
>>> register_method(Method("silence", "plays nothing (an example)", silence))
>>> "silence" in method_names()
True
>>> unregister_method("silence")
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from data_schemas.errors import ParameterError

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd

    from pipelines.methods.result import MethodOutput


@dataclass(frozen=True)
class Method:
    """A registered rendering method.

    Attributes
    ----------
    name : str
        Name used by ``--method``/``--methods`` and :func:`get_method`.
    summary : str
        One line for ``--help`` and the comparison report.
    render : callable
        ``render(notes, parts, *, config, database, models, seed, sample_rate, instrument,
        skill, transpose_octaves, diagnostics, progress, engine)`` -> list of
        :class:`~pipelines.methods.result.PartOutput` (one per part index in ``parts``).
    needs_db : bool
        Plays gestures from a gesture database (``database`` is an opened
        :class:`~pipelines.methods.sampling.SamplingDatabase`).
    needs_models : bool
        Listens with trained listening models (``models`` is their directory).
    """

    name: str
    summary: str
    render: Callable[..., list]
    needs_db: bool = False
    needs_models: bool = False


def lazy(target: str) -> Callable[..., Any]:
    """A callable that imports ``"package.module:function"`` when first called."""
    module, _, attr = target.partition(":")

    def call(*args: Any, **kwargs: Any) -> Any:
        return getattr(importlib.import_module(module), attr)(*args, **kwargs)

    call.__name__ = call.__qualname__ = attr
    call.__doc__ = f"Calls :func:`{module}.{attr}` (imported on first use)."
    return call


#: The built-in methods, in the order ``--help`` and reports list them.
BUILTIN = (
    Method("rules", "performance rules (notation -> bowing), open loop",
           lazy("pipelines.methods.builtin:play_rules")),
    Method("feedback", "rules' bowing, force chosen by the listening controller",
           lazy("pipelines.methods.builtin:play_feedback"), needs_models=True),
    Method("sampling", "gestures sampled from the database, force corrected by the controller",
           lazy("pipelines.methods.builtin:play_sampling"), needs_db=True, needs_models=True),
    Method("sampling-open", "gestures sampled from the database, open loop",
           lazy("pipelines.methods.builtin:play_sampling_open"), needs_db=True),
)

_REGISTRY: dict[str, Method] = {m.name: m for m in BUILTIN}


def register_method(method: Method) -> None:
    """Add ``method`` to the registry.

    Raises
    ------
    ParameterError
        A method of that name is already registered.
    """
    if method.name in _REGISTRY:
        raise ParameterError(f"method {method.name!r} is already registered")
    _REGISTRY[method.name] = method


def unregister_method(name: str) -> None:
    """Remove method ``name`` (no error if it is absent)."""
    _REGISTRY.pop(name, None)


def method_names() -> list[str]:
    """Names of the registered methods, built-in ones first in their order."""
    return list(_REGISTRY)


def get_method(name: str, *, option: str = "--method") -> Method:
    """The registered method ``name``.

    Raises
    ------
    ParameterError
        Unknown name (the message lists the known ones).
    """
    if name not in _REGISTRY:
        raise ParameterError(f"{option} {name}: unknown method (choose from: "
                             f"{', '.join(_REGISTRY)})")
    return _REGISTRY[name]


class _Summaries(Mapping):
    """Read-only view: method name -> summary, always in step with the registry."""

    def __getitem__(self, name: str) -> str:
        return _REGISTRY[name].summary

    def __iter__(self) -> Iterator[str]:
        return iter(_REGISTRY)

    def __len__(self) -> int:
        return len(_REGISTRY)


#: Method name -> one-line summary (a live view of the registry).
METHODS: Mapping[str, str] = _Summaries()


def check_methods(methods: list[str], *, db, models, option: str = "--methods") -> None:
    """Raise :class:`ParameterError` for unknown methods or a missing --db / --models."""
    if not methods:
        raise ParameterError(f"{option}: no method given (choose from: "
                             f"{', '.join(_REGISTRY)})")
    chosen = [get_method(m, option=option) for m in methods]
    need_db = [m.name for m in chosen if m.needs_db]
    need_models = [m.name for m in chosen if m.needs_models]
    if db is None and need_db:
        raise ParameterError(f"{', '.join(need_db)}: need --db DB (a gesture database from "
                             "arco build-db)")
    if models is None and need_models:
        raise ParameterError(f"{', '.join(need_models)}: need --models DIR (listening models "
                             "from arco train)")
    if models is not None and not Path(models).is_dir():
        raise ParameterError(f"--models {models}: no such directory")


def render_method(method: str, notes: pd.DataFrame, parts: list[int], *, stem: str,
                  config: dict[str, Any], database=None, models=None, seed: int = 0,
                  sample_rate: int = 44100, instrument: str | None = None, skill: int = 3,
                  transpose_octaves: bool = False, diagnostics: bool = True,
                  progress: bool | None = False, engine: str = "modal",
                  max_duration: float | None = None,
                  max_notes: int | None = None, spool=None) -> MethodOutput:
    """Render the chosen parts of one score with one method and mix them.

    Parameters
    ----------
    method : str
        A registered method (:func:`method_names`).
    notes : pandas.DataFrame
        Notes table of the whole score (fermatas of every part make every part wait).
    parts : list of int
        Part indices to render, each on its own instrument.
    stem : str
        Name of the piece (the score's file name without extension).
    config : dict
        Rules configuration.
    database : SamplingDatabase, optional
        Opened gesture database (methods that need one).
    models : path-like, optional
        Listening models (methods that need them).
    seed : int
    sample_rate : int, Hz
    instrument : str, optional
        Override the part's instrument (one part only).
    skill : int
        Vivi's skill level 0..3 (the rules-planned methods).
    transpose_octaves : bool
        Fold out-of-range notes by octaves.
    diagnostics : bool
        Record the instrument's per-hop contact diagnostics.
    progress : bool, optional
        Progress bars.
    engine : str
        Synthesis engine (:func:`synth.engines.engine_names`).
    max_duration : float, optional, s
        Longest performance allowed (default :data:`data_schemas.limits.LIMITS`).
    max_notes : int, optional
        Most notes allowed in the chosen parts (default as ``max_duration``).
    spool : pipelines.ensemble.spool.AudioSpool, optional
        Keep each part's audio on disk as it is rendered (rules and feedback do it part
        by part; any other method's parts are spooled when it returns); the parts' and the
        mix's ``audio`` are then empty.

    Returns
    -------
    MethodOutput

    Raises
    ------
    ParameterError
        The chosen parts are longer or hold more notes than allowed (before any work).
    """
    from pipelines.methods.result import MethodOutput, mix

    if instrument is not None and len(parts) > 1:
        raise ParameterError("--instrument applies to a single part (drop --all-parts)")
    _check_bounds(notes, parts, stem, max_duration, max_notes)
    start = time.perf_counter()
    out = get_method(method).render(
        notes, parts, config=config, database=database, models=models, seed=seed,
        sample_rate=sample_rate, instrument=instrument, skill=skill,
        transpose_octaves=transpose_octaves, diagnostics=diagnostics, progress=progress,
        engine=engine, **({} if spool is None else {"spool": spool}))
    for part in out if spool is not None else []:
        if part.audio.size or part.part_index not in spool.paths:
            part.audio = spool.put(part.part_index, part.audio)
    seconds = time.perf_counter() - start
    return MethodOutput(method, stem, mix([p.audio for p in out]), out, seconds)


def _check_bounds(notes: pd.DataFrame, parts: list[int], stem: str,
                  max_duration: float | None, max_notes: int | None) -> None:
    """The chosen parts' note count and last note end, against the limits."""
    from data_schemas.limits import check_duration, check_note_count

    chosen = notes[notes["part_index"].isin(parts)] if "part_index" in notes else notes
    source = stem
    if "source_file" in chosen and len(chosen):
        source = str(chosen["source_file"].iloc[0])
    check_note_count(len(chosen), source, max_notes)
    if len(chosen) and {"onset", "duration"} <= set(chosen.columns):
        check_duration(float((chosen["onset"] + chosen["duration"]).max()), source, max_duration)


def __getattr__(name: str) -> Any:
    """``MethodOutput`` and ``PartOutput`` now live in :mod:`pipelines.methods.result`."""
    if name in ("MethodOutput", "PartOutput"):
        from pipelines.methods import result

        return getattr(result, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
