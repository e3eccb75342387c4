"""The Python API: lazy package exports and the methods registry."""

from __future__ import annotations

import importlib
import subprocess
import sys

import numpy as np
import pytest

from data_schemas.errors import ParameterError
from data_schemas.lazy import typing_imports

PACKAGES = ("data_schemas", "gesture_db", "synth", "pipelines", "pipelines.score")
HEAVY = ("numpy", "pandas", "pyarrow", "scipy", "numba", "sklearn", "music21", "librosa",
         "matplotlib", "dask")


@pytest.mark.parametrize("name", PACKAGES)
def test_every_exported_name_is_the_defining_modules_object(name):
    package = importlib.import_module(name)
    where = typing_imports(package.__file__)
    assert sorted(package.__all__) == sorted(where)
    for attr, module in where.items():
        assert getattr(package, attr) is getattr(importlib.import_module(module), attr)
    with pytest.raises(AttributeError, match="no attribute 'nonesuch'"):
        package.nonesuch  # noqa: B018


def test_importing_the_packages_imports_nothing_heavy():
    code = ("import sys\nimport data_schemas, gesture_db, synth, pipelines, pipelines.score\n"
            "from data_schemas import ParameterError\nfrom synth import engine_names\n"
            "from pipelines.methods.registry import method_names\n"
            "engine_names(), method_names()\n"
            f"print('HEAVY', sorted(m for m in {HEAVY!r} if m in sys.modules))\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60)
    assert "HEAVY []" in run.stdout, run.stdout + run.stderr


def test_a_registered_method_is_rendered_by_render_score():
    from pipelines import Method, PartOutput, register_method, render_score
    from pipelines.methods.feedback import scale_notes
    from pipelines.methods.registry import unregister_method

    seen = {}

    def hum(notes, parts, *, seed, engine, **settings):
        seen.update(parts=parts, seed=seed, engine=engine)
        return [PartOutput(i, "hum", "violin", np.full(100, 0.1, np.float32), notes.iloc[:0],
                           notes.iloc[:0], None, notes) for i in parts]

    register_method(Method("hum", "a constant (a test method)", hum))
    try:
        with pytest.raises(ParameterError, match="already registered"):
            register_method(Method("hum", "again", hum))
        out = render_score(scale_notes(octaves=1), method="hum", seed=7)
    finally:
        unregister_method("hum")
    assert seen == {"parts": [0], "seed": 7, "engine": "modal"}
    assert out.method == "hum" and out.audio.tolist() == pytest.approx([0.1] * 100)


@pytest.mark.parametrize("methods, db, models, message", [
    (["nonesuch"], None, None, "--methods nonesuch: unknown method (choose from: rules,"),
    ([], None, None, "no method given"),
    (["rules", "sampling-open"], None, None, "sampling-open: need --db DB"),
    (["feedback", "sampling"], "db", None, "feedback, sampling: need --models DIR"),
    (["rules"], None, "/nonexistent/models", "--models /nonexistent/models: no such"),
])
def test_check_methods_names_what_is_missing(methods, db, models, message):
    from pipelines import check_methods

    with pytest.raises(ParameterError) as err:
        check_methods(methods, db=db, models=models)
    assert message in str(err.value)


def test_methods_view_follows_the_registry():
    from pipelines.methods.registry import BUILTIN, METHODS, method_names

    assert list(METHODS) == method_names() == [m.name for m in BUILTIN]
    assert METHODS["sampling-open"] == BUILTIN[3].summary
