# Everything goes through .venv; each target creates it on first use.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEMO_STAMP := $(VENV)/.demo-installed

.PHONY: demo test lint typecheck pytest docs notebooks bench bench-coverage fuzz gpu-check clean

# .venv with the package and the extras $(1), then the stamp ($@).
define install
	@bash tools/ensure_gl.sh
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[$(1)]'
	touch $@
endef

$(STAMP): pyproject.toml
	$(call install,dev)

# What the demo needs only (the render extra: moderngl, Pillow, wgpu; seconds, not the
# development toolchain); `make test` adds the rest to the same .venv.
$(DEMO_STAMP): pyproject.toml
	$(call install,render)

## The main job: the default scene (see README). Options: make demo ARGS="--help"
demo: $(DEMO_STAMP)
	$(PY) -m shadowmath $(ARGS)

## The whole suite: lint, strict typing, tests, the docs site and the notebooks, two at a
## time (pytest itself on every core: JOBS=auto workers, each with its own GL context;
## JOBS=0 runs it in one process). The docs build runs every notebook (mkdocs.yml:
## mkdocs-jupyter, execute: true, allow_errors: false): a failing cell fails it, so the
## notebooks target is not run a second time here.
test: $(STAMP)
	$(MAKE) --no-print-directory -j2 --output-sync=target lint typecheck pytest docs

lint: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .

typecheck: $(STAMP)
	$(PY) -m mypy

JOBS ?= auto
pytest: $(STAMP)
	$(PY) -m pytest -n $(JOBS) --dist loadfile --durations=20

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --quiet

## The notebooks alone, each as a test (nbmake); `make test` runs them in the docs build.
notebooks: $(STAMP)
	$(PY) -m pytest --nbmake notebooks

## The benchmark suite (not a test; prints tables): speed against PyGLM, NumPy and the memory
## limit, and the optimized fit's coverage. Options: make bench ARGS="--help" (--only, --tiny, --json).
bench: $(STAMP)
	$(PY) benchmarks/run.py $(ARGS)

## Coverage of the optimized frustum fit vs the article's MDV set-up alone (bench's last section).
bench-coverage: $(STAMP)
	$(PY) benchmarks/bench_fit.py $(ARGS)

## The long fuzz run (2000 examples per fuzz test instead of 25); prints the cases tried.
fuzz: $(STAMP)
	HYPOTHESIS_PROFILE=fuzz $(PY) -m pytest -q tests/test_fuzz.py $(ARGS)

## The render suite (SHADOWMATH_REQUIRE_GL=1) and bench's GPU section on this machine's GPU,
## after printing what they run on; without a GPU it says so and runs nothing. Needs no
## package registry: uses .venv if there is one, else GPU_PYTHON (docs/accuracy.md).
GPU_PYTHON ?= $(if $(wildcard $(PY)),$(PY),$(PYTHON))
gpu-check:
	$(GPU_PYTHON) tools/gpu_check.py $(ARGS)

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache .hypothesis site out
