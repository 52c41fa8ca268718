# Two entry points (see README): `make demo` and `make test`.
# Each creates or reuses .venv and installs what it needs.
PYTHON ?= python3.11
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null || { echo "need $(PYTHON)"; exit 1; }
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	@if ! dpkg -s libegl1 libegl-mesa0 libgl1 >/dev/null 2>&1; then \
		(apt-get update -qq && apt-get install -y -qq libegl1 libegl-mesa0 libgl1 >/dev/null) \
		|| echo "warning: could not install Mesa EGL packages; video rendering may fail"; fi
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e ".[dev]"
	@touch $(STAMP)

demo: $(STAMP)
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

test: $(STAMP)
	$(VENV)/bin/ruff check src tests benchmarks
	$(VENV)/bin/ruff format --check src tests benchmarks
	$(VENV)/bin/mypy
	MUJOCO_GL=egl $(VENV)/bin/pytest -q

bench: $(STAMP)
	$(PY) benchmarks/bench_sim.py

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info
