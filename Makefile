# Set-up and entry points. `make demo` and `make test` each do the whole set-up on a fresh machine:
# a libLLVM >= 16 for Dr.Jit (Debian's libllvm19 when missing), a virtual environment in .venv with
# the versions pinned in constraints.txt (only what the job needs: no PyTorch for the demo and tests),
# then the job itself.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
LLVM := $(shell scripts/ensure_llvm.sh)
export DRJIT_LIBLLVM_PATH ?= $(LLVM)

.PHONY: setup demo test bench clean

$(VENV)/.installed: pyproject.toml constraints.txt
	test -x $(PY) || { $(PYTHON) -m venv $(VENV) && touch $(VENV)/.made-by-make; }  # a venv the user made (any Python 3.11) is used as it is
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c constraints.txt -e ".[test]"
	touch $@

setup: $(VENV)/.installed

demo: setup
	$(PY) scripts/demo.py

test: setup
	$(PY) -m pytest -q

bench: setup
	$(PY) -m pip install --quiet -c constraints.txt -e ".[bench]"
	$(PY) scripts/bench.py

# removes only the venv this Makefile made; out/ holds results (the demo's, the bench's) and is left to the user
clean:
	@if [ -f $(VENV)/.made-by-make ]; then rm -rf $(VENV); echo "removed $(VENV)"; \
	elif [ -e $(VENV) ]; then echo "$(VENV): not made by make (no .made-by-make in it), so it is kept"; fi
