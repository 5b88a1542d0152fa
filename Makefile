# Quick start: `make run` (set up .venv, open the app on an example) and `make test`.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
EXAMPLE ?= examples/creature.json
PLUGINS := plugins/inflate plugins/isophote_tool plugins/assemble plugins/animate

.PHONY: run test venv bench screenshots clean

venv: $(STAMP)

# Re-install whenever a pyproject changes (a new dependency lands with its commit).
$(STAMP): pyproject.toml $(addsuffix /pyproject.toml,$(PLUGINS))
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[test]' $(addprefix -e ,$(PLUGINS))
	touch $@

run: $(STAMP)
	$(BIN)/sketchforge $(EXAMPLE)

# The whole suite. Qt runs offscreen; the few OpenGL tests start their own Xvfb
# (pytest-xvfb) and are skipped where no Xvfb binary exists.
test: $(STAMP)
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m pytest -q $(PYTEST_ARGS)

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(BIN)/python $$b || exit 1; done

# Regenerate the README's screenshots (observation needs OpenGL: Xvfb + Mesa).
screenshots: $(STAMP)
	QT_QPA_PLATFORM=offscreen $(BIN)/python -m sketchforge.qt.screenshots $(EXAMPLE) docs/screenshots
	xvfb-run -a env QT_QPA_PLATFORM=xcb $(BIN)/sketchforge --screenshot docs/screenshots/observation.png $(EXAMPLE) --mode observation
	$(BIN)/python examples/make_animated.py --strip docs/screenshots/animation_strip.png

clean:
	rm -rf $(VENV) build *.egg-info plugins/*/*.egg-info
