"""Score reading, performance rules, rendering methods, reports and the arco CLI.

The score-to-audio path from Python; every name loads on first use (PEP 562,
:mod:`data_schemas.lazy`), so ``import pipelines`` is light.

Examples
--------
Read the bundled quartet, then play the first violin's first measure with the rules on the
modal engine:

>>> from pipelines import bundled_score, read_score, render_score
>>> notes = read_score(bundled_score())
>>> sorted(notes["part_index"].unique().tolist())
[0, 1, 2, 3]
>>> out = render_score(notes, method="rules", engine="modal", parts=0, end_measure=1)
>>> out.parts[0].part_index, len(out.parts[0].actions) > 0
(0, True)

The methods and what they need:

>>> from pipelines import get_method, method_names
>>> [(m, get_method(m).needs_db) for m in method_names()]
[('rules', False), ('feedback', False), ('sampling', True), ('sampling-open', True)]
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from data_schemas.lazy import lazy_exports

if TYPE_CHECKING:  # pragma: no cover - where each name lives (read by lazy_exports)
    from pipelines.listening.evaluate import evaluate
    from pipelines.methods.registry import (
        Method,
        check_methods,
        get_method,
        method_names,
        register_method,
        render_method,
    )
    from pipelines.methods.render import render_score
    from pipelines.methods.result import MethodOutput, PartOutput, mix
    from pipelines.perform.config import load_config
    from pipelines.reports.compare import compare
    from pipelines.score.bundled import bundled_score
    from pipelines.score.dispatch import read_score
    from pipelines.score.select import choose_parts, select_measures

__all__ = ["Method", "MethodOutput", "PartOutput", "bundled_score", "check_methods",
           "choose_parts", "compare", "evaluate", "get_method", "load_config", "method_names",
           "mix", "read_score", "register_method", "render_method", "render_score",
           "select_measures"]

__getattr__, __dir__ = lazy_exports(__name__, __file__)
