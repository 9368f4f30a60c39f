# The README's two commands. Each sets everything up first, once: a virtual environment in
# .venv, PyTorch's CPU build, the package with its test extra, the plants' kernels compiled
# ahead. Needs Python >= 3.10 (PYTHON=python3.12 make ... picks another) and make.
#
#   make leaderboard   # every plant, policy, scenario and seed into leaderboard_out/
#   make test          # the tests (slow ones excluded)
#
# The set-up is redone when pyproject.toml changes (or `make clean`). TORCH_INDEX is the
# index of PyTorch's CPU wheels; where it cannot be reached, the pinned release comes from
# the machine's own package index.

PYTHON ?= python3
VENV ?= .venv
TORCH ?= torch==2.13.0
TORCH_INDEX ?= https://download.pytorch.org/whl/cpu
OUT ?= leaderboard_out
BIN := $(VENV)/bin
READY := $(VENV)/.steamtemp-ready

.PHONY: setup leaderboard test clean

setup: $(READY)

$(READY): pyproject.toml
	@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 10))' || \
		{ echo "steamtemp_gym needs Python >= 3.10; $(PYTHON) is older (PYTHON=... make)"; exit 1; }
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	@$(BIN)/python -c "import torch" 2>/dev/null || \
		$(BIN)/python -m pip install -q --timeout 20 --retries 1 $(TORCH) --index-url $(TORCH_INDEX) || \
		$(BIN)/python -m pip install -q $(TORCH)
	$(BIN)/python -m pip install -q -e ".[test]"
	$(BIN)/python -m steamtemp_gym.precompile
	@touch $@

leaderboard: setup
	$(BIN)/steamtemp-leaderboard --out $(OUT)

test: setup
	$(BIN)/python -m pytest -n 2 -q

clean:
	rm -f $(READY)
