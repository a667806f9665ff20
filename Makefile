# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp
export QT_QPA_PLATFORM ?= offscreen

.PHONY: demo demo-quick test test-all bench screenshots package clean

$(STAMP): pyproject.toml
	test -x $(PY) || python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/lps demo --out demo-output

demo-quick: $(STAMP)
	$(VENV)/bin/lps demo --quick --out demo-output-quick

test: $(STAMP)
	$(PY) -m pytest -m "not slow"

test-all: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	for b in benchmarks/bench_*.py; do $(PY) $$b || exit 1; done

screenshots: $(STAMP)
	$(PY) -m lps_gui.gui.screenshots docs/screenshots

package: $(STAMP)
	$(PY) -m pip install -q -e '.[package]'
	$(VENV)/bin/pyinstaller --noconfirm --distpath dist --workpath build packaging/lps-gui.spec

clean:
	rm -rf build dist demo-output demo-output-quick .pytest_cache
