# Two commands do all set-up on a fresh machine:
#   make demo   install, then diagnose the bundled EMPS hardware recordings
#   make test   install, then run the test suite (long tests: make test-slow)
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup demo test test-slow bench clean

setup: $(STAMP)

$(STAMP): pyproject.toml constraints-cpu.txt
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -c constraints-cpu.txt -e ".[dev]"
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

clean:
	rm -rf $(VENV) runs .pytest_cache
