# SPDX-License-Identifier: GPL-3.0-or-later
# Bounce GI — two commands for a fresh machine: `make demo` and `make test`.
SHELL := /bin/bash
PYENV_ROOT ?= $(shell pyenv root 2>/dev/null || echo $$HOME/.pyenv)
# Python 3.13 found by path (bpy 5.2 needs exactly 3.13); the bare python3.13 shim refuses without PYENV_VERSION.
PY313 ?= $(firstword $(wildcard $(PYENV_ROOT)/versions/3.13*/bin/python3.13) $(shell command -v python3.13 2>/dev/null))
VENV := .venv
PY := $(VENV)/bin/python
# System libraries bpy needs even headless, and Mesa's EGL + llvmpipe for moderngl without a GPU.
APT_PACKAGES := libx11-6 libxi6 libxfixes3 libxrender1 libxkbcommon0 libsm6 libice6 libxext6 libgl1 \
                libegl1 libegl-mesa0 libgl1-mesa-dri
STAMP := $(VENV)/.setup-done

.PHONY: setup demo test test-fast bench bench-edits package clean system-libs

setup: $(STAMP)

$(STAMP): requirements.txt pyproject.toml
	@$(MAKE) --no-print-directory system-libs
	@if [ -z "$(PY313)" ]; then echo "error: Python 3.13 not found under $(PYENV_ROOT)/versions (bpy 5.2 needs it)"; exit 2; fi
	@test -x $(PY) || $(PY313) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements.txt
	$(PY) -m pip install -q --no-deps -e .
	@touch $(STAMP)

system-libs:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "installing system libraries:$$missing"; \
	  SUDO=""; [ "$$(id -u)" = 0 ] || SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	fi

demo: setup
	$(PY) examples/demo.py --out out/demo

test: setup
	$(PY) -m pytest -q

# The unit and GPU tests alone (no Blender, no Cycles), on two worker processes: the quick loop while editing the
# core. (make test stays in one process: the accuracy tests share their Cycles references within a session.)
test-fast: setup
	$(PY) -m pytest -q -n 2 -m "unit or gpu"

# The committed benchmark (benchmarks/results/<renderer>/): example scenes at 160x120 against Cycles (± OIDN) and
# EEVEE (its timed second render takes ~70 s per scene here), incremental updates, scaling; its quality table
# becomes the one automatic quality reads (addon/).
BENCH_SCENES = cornell spot_room courtyard
BENCH_OUT ?= benchmarks/results/llvmpipe
bench: setup
	$(PY) examples/build_examples.py out/ex $(BENCH_SCENES)
	$(VENV)/bin/bounce-gi bench $(BENCH_SCENES:%=out/ex/%.blend) --res 160 120 --out $(BENCH_OUT)
	$(VENV)/bin/bounce-gi bench $(BENCH_SCENES:%=out/ex/%.blend) --incremental --res 160 120 --out $(BENCH_OUT)
	$(VENV)/bin/bounce-gi bench --scaling > $(BENCH_OUT)/scaling.md
	cp $(BENCH_OUT)/quality_front.json addon/quality_front.json

# What an edit costs on every example scene, LPV (about 15 min here): benchmarks/results/<renderer>/incremental_run.md,
# the tables incremental.md's notes are written from.
EDIT_SCENES = $(BENCH_SCENES) default_principled metals textured window_room rug_room thin_walls lamp_room \
	many_lights outdoor product_shot furnished cornell_animated
bench-edits: setup
	$(PY) examples/build_examples.py out/ex $(EDIT_SCENES)
	$(VENV)/bin/bounce-gi bench $(EDIT_SCENES:%=out/ex/%.blend) --incremental --methods lpv --res 160 120 \
		--out $(BENCH_OUT)

package: setup
	$(PY) tools/package.py

clean:
	rm -rf out dist build *.egg-info
