# Arco: two commands get you going -- `make demo` and `make test`.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
NPROC := $(shell nproc 2>/dev/null || echo 2)

.PHONY: demo test fuzz bench lint venv clean stk peers

venv: $(STAMP)

$(STAMP): pyproject.toml constraints.txt
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need $(PYTHON)"; exit 1; }
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c constraints.txt -e ".[dev]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/arco demo -o out

test: $(STAMP)
	$(BIN)/python -m pytest -q -n $(NPROC) --dist loadfile

# Many more fresh random mutations of every reader than make test's few (tests/test_fuzz.py).
FUZZ_EXAMPLES ?= 300
fuzz: $(STAMP)
	ARCO_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) ARCO_FUZZ_RANDOM=1 $(BIN)/python -m pytest -q \
	  -n $(NPROC) tests/test_fuzz.py

lint: $(STAMP)
	$(BIN)/ruff check .

# Every benchmark prints one JSON object; the listening models trained by feedback_speed
# are reused by sampling_speed (out/bench-models).
bench: $(STAMP) stk peers
	$(BIN)/python bench/cli_speed.py --json
	$(BIN)/python bench/synth_speed.py --json
	$(BIN)/python bench/score_speed.py --json
	$(BIN)/python bench/build_db.py --json
	$(BIN)/python bench/feedback_speed.py --json --workers 2 --models out/bench-models
	$(BIN)/python bench/sampling_speed.py --json --models out/bench-models
	$(BIN)/python bench/timbre.py --json
	$(BIN)/python bench/playability.py --json --workers 2

# STK's Bowed waveguide is the speed peer of bench/synth_speed.py (Debian's libstk-dev).
stk:
	@if ! ls /usr/include/stk/Bowed.h >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && apt-get install -y -qq libstk-dev g++ >/dev/null; \
	  else sudo apt-get update -qq && sudo apt-get install -y -qq libstk-dev g++ >/dev/null; fi; \
	fi

# Artifastring (shared/peers, built by its run.sh: g++, libfftw3-dev) and FluidR3 through
# fluidsynth (fluidsynth, fluid-soundfont-gm): the peers of synth_speed.py and timbre.py.
peers:
	@if ! ls /usr/include/fftw3.h /usr/share/sounds/sf2/FluidR3_GM.sf2 >/dev/null 2>&1 \
	    || ! command -v fluidsynth >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	  $$SUDO apt-get update -qq && $$SUDO apt-get install -y -qq g++ libfftw3-dev fluidsynth \
	    fluid-soundfont-gm >/dev/null; \
	fi

clean:
	rm -rf $(VENV) out .pytest_cache .ruff_cache
