# Two commands do all set-up on a fresh machine:
#   make demo   install, then diagnose the bundled EMPS hardware recordings
#   make test   install, then run the test suite (long tests: make test-slow)
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup demo test test-slow bench docs clean

setup: $(STAMP)

$(STAMP): pyproject.toml constraints-cpu.txt
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -c constraints-cpu.txt -e ".[dev]"
	# MuJoCo Playground for the interop tests, without its warp-lang dependency (149 MB, MJX's
	# GPU backend: sim2real runs MJX's JAX implementation, and Playground tasks are loaded with it)
	$(PY) -m pip install -q --no-deps -c constraints-cpu.txt playground
	touch $(STAMP)

demo: setup
	$(PY) scripts/diagnose.py out=runs/emps_diagnosis overwrite=true

# two workers (the CI machine has 2 cores), one test file per worker: files share compiled
# rollouts through module-level caches
test: setup
	$(PY) -m pytest -q -n 2 --dist loadfile

test-slow: setup
	$(PY) -m pytest -q -m slow

bench: setup
	$(PY) -m pip install -q -c constraints-cpu.txt -e ".[bench]"
	$(PY) benchmarks/throughput.py tag=cpu-2core

# the API reference from the docstrings (pdoc), every public module: docs/api/index.html
docs: setup
	$(PY) -m pip install -q -c constraints-cpu.txt pdoc
	$(PY) -m pdoc -o docs/api --docformat google $$($(PY) -c "import pkgutil, sim2real; print(' '.join(['sim2real'] + [m.name for m in pkgutil.walk_packages(sim2real.__path__, 'sim2real.') if '._' not in m.name and not m.name.endswith('__main__')]))")
	@echo "API reference: docs/api/index.html"

clean:
	rm -rf $(VENV) runs .pytest_cache docs/api
