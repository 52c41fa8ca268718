# Two entry points (see README): `make demo` and `make test`.
# Each creates or reuses .venv and installs what it needs: `make demo` the library and the
# CLI only (no torch, ray, gymnasium or test tools), `make test` the `dev` extra (tools and
# every optional extra). One stamp file per level, so `make test` after `make demo` adds
# the dev extra, and either reinstalls when pyproject.toml changes.
PYTHON ?= python3.11
VENV := .venv
PY := $(VENV)/bin/python
BASE_STAMP := $(VENV)/.installed-base
DEV_STAMP := $(VENV)/.installed-dev

.PHONY: demo test lint bench clean

# the venv, Mesa's EGL (offscreen video) and a current pip: what both levels need first
define prepare_venv
	@command -v $(PYTHON) >/dev/null || { echo "need $(PYTHON)"; exit 1; }
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@if ! dpkg -s libegl1 libegl-mesa0 libgl1 >/dev/null 2>&1; then \
		(apt-get update -qq && apt-get install -y -qq libegl1 libegl-mesa0 libgl1 >/dev/null) \
		|| echo "warning: could not install Mesa EGL packages; video rendering may fail"; fi
	$(PY) -m pip install -q --upgrade pip
endef

$(BASE_STAMP): pyproject.toml
	$(prepare_venv)
	$(PY) -m pip install -q -e .
	@touch $(BASE_STAMP)

# the dev extra includes the base install, so it satisfies `make demo` too
$(DEV_STAMP): pyproject.toml
	$(prepare_venv)
	$(PY) -m pip install -q -e ".[dev]"
	@touch $(BASE_STAMP) $(DEV_STAMP)

demo: $(BASE_STAMP)
	MUJOCO_GL=egl $(VENV)/bin/gaitnet-mpc run --robot humanoid3d --controller kd \
		--course stepping-stones --vx 0.75 --dt 0.045 --duration 6 --out runs/demo/stepping-stones --overwrite
	MUJOCO_GL=egl $(VENV)/bin/gaitnet-mpc run --robot humanoid3d --controller gaitnet \
		--course stepping-stones --vx 0.75 --duration 6 --out runs/demo/stepping-stones-gaitnet \
		--overwrite
	MUJOCO_GL=egl $(VENV)/bin/gaitnet-mpc run --robot humanoid3d --controller kd \
		--course stepping-stones --vx 0.75 --dt 0.05 --preview --duration 6 \
		--out runs/demo/stepping-stones-preview --overwrite
	MUJOCO_GL=egl $(VENV)/bin/gaitnet-mpc run --robot humanoid3d --controller kd --course gap \
		--vx 0.75 --dt 0.055 --duration 6 --out runs/demo/gap --overwrite
	$(VENV)/bin/gaitnet-mpc compare runs/demo/stepping-stones runs/demo/stepping-stones-gaitnet \
		runs/demo/stepping-stones-preview runs/demo/gap --out runs/demo/compare

test: $(DEV_STAMP) lint
	MUJOCO_GL=egl $(VENV)/bin/pytest -q

lint: $(DEV_STAMP)
	$(VENV)/bin/ruff check src tests benchmarks examples
	$(VENV)/bin/ruff format --check src tests benchmarks examples
	$(VENV)/bin/mypy

bench: $(BASE_STAMP)
	$(PY) benchmarks/bench_sim.py

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info
