# Quick start: `make run` (set up .venv, open the app on an example) and `make test`.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
EXAMPLE ?= examples/creature.json
PLUGINS := plugins/inflate plugins/isophote_tool plugins/assemble plugins/animate plugins/strips
# Example plugin packages (a BRDF, a brush, an exporter): installed like any plugin so that
# `make test` runs their own tests (pyproject's testpaths) against sketchforge's fixtures.
EXAMPLE_PLUGINS := examples/plugins/soft_brdf examples/plugins/bump_brush examples/plugins/off_exporter

.PHONY: run deps lint test venv bench mutate screenshots clean

# What Qt's xcb window plugin needs on a minimal Debian/Ubuntu image (the same list as
# sketchforge/qt/platform_check.py's XCB_LIBRARIES; a test keeps the two equal).
DEB_PACKAGES := libxcb1 libx11-xcb1 libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0 \
	libxcb-cursor0 libxcb-randr0 libxcb-render0 libxcb-shape0 libxcb-shm0 libxcb-sync1 libxcb-util1 \
	libxcb-xfixes0 libxcb-xkb1 libxkbcommon0 libxkbcommon-x11-0 libegl1 libgl1 libfontconfig1 libdbus-1-3
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)

venv: $(STAMP)

# Re-install whenever a pyproject changes (a new dependency lands with its commit).
$(STAMP): pyproject.toml $(addsuffix /pyproject.toml,$(PLUGINS) $(EXAMPLE_PLUGINS))
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test,dev]' $(addprefix -e ,$(PLUGINS) $(EXAMPLE_PLUGINS))
	touch $@

# Checks first that a window can open (display, xcb libraries): if not, the last line says
# what to install (`make deps`) or to use xvfb-run, instead of Qt's abort text.
run: $(STAMP)
	@if problem=$$($(BIN)/python -m sketchforge.qt.platform_check); then \
		$(BIN)/sketchforge $(EXAMPLE); \
	else echo "$$problem"; exit 2; fi

# Installs the system libraries Qt's window plugin needs (Debian/Ubuntu, apt).
deps:
	$(SUDO) apt-get install -y --no-install-recommends $(DEB_PACKAGES)

# Lint and types, first in `make test` (so CI runs them): ruff on the whole tree, then mypy
# on sketchforge/ and plugins/ held to mypy-baseline.json (tools/check_types.py: a module's
# error count may only go down). Configuration: pyproject.toml's [tool.ruff] and [tool.mypy].
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python tools/check_types.py

# The whole suite. Qt runs offscreen; the few OpenGL tests start their own Xvfb
# (pytest-xvfb) and are skipped where no Xvfb binary exists.
test: $(STAMP) lint
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m pytest -q $(PYTEST_ARGS)

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

# Mutation testing (mutmut), on demand, not in CI: `make mutate SCOPE=document` (or geometry, plugins, core, strips,
# inflate, isophote_tool, assemble, animate, all). Scores and survivors go to mutation/results/;
# a second run re-tests only what changed. Hours of CPU for `all` on 2 cores; SAMPLE=150 checks
# a seeded sample of the unchecked mutants instead and estimates the scope's score from it.
SCOPE ?= document
SAMPLE ?=
mutate: $(STAMP)
	$(BIN)/python -m pip install -q -e '.[test,mutation]'
	$(BIN)/python mutation/run.py $(SCOPE) $(if $(SAMPLE),--sample $(SAMPLE))

# Regenerate the README's screenshots (observation needs OpenGL: Xvfb + Mesa).
screenshots: $(STAMP)
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m sketchforge.qt.screenshots $(EXAMPLE) docs/screenshots
	tmp=$$(mktemp -d) && \
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m sketchforge.qt.drawing_strip docs/screenshots --save $$tmp/creature.json && \
	xvfb-run -a env QT_QPA_PLATFORM=xcb $(BIN)/sketchforge --screenshot docs/screenshots/drawing-7-observation.png $$tmp/creature.json --mode observation; \
	rc=$$?; rm -rf $$tmp; exit $$rc
	xvfb-run -a env QT_QPA_PLATFORM=xcb $(BIN)/sketchforge --screenshot docs/screenshots/observation.png $(EXAMPLE) --mode observation
	$(BIN)/python examples/make_animated.py --strip docs/screenshots/animation_strip.png

clean:
	rm -rf $(VENV) build *.egg-info plugins/*/*.egg-info examples/plugins/*/*.egg-info
