# Set-up and entry points. `make demo` and `make test` each do the whole set-up on a fresh machine:
# a libLLVM >= 16 for Dr.Jit (Debian's libllvm19 when missing), a virtual environment in .venv with
# the pinned dependencies, then the job itself.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
LLVM := $(shell scripts/ensure_llvm.sh)
export DRJIT_LIBLLVM_PATH ?= $(LLVM)

.PHONY: setup demo test bench clean

$(VENV)/.installed: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,clip]"
	touch $@

setup: $(VENV)/.installed

demo: setup
	$(PY) scripts/demo.py

test: setup
	$(PY) -m pytest -q

bench: setup
	$(PY) scripts/bench.py

clean:
	rm -rf $(VENV) out
